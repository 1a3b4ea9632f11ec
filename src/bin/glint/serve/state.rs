//! What the server keeps: the served scene (the last good one, and the
//! latest parse error), the worlds built from it, the sessions and their
//! progressive renders, and the bounds on concurrent work.

use super::params::Defaults;
use glint::accel::AccelKind;
use glint::format::{load_scene_gated, ParseError};
use glint::math::Vec3;
use glint::render::PixelCost;
use glint::scene::Scene;
use glint::world::{BuildOptions, World};
use serde_json::json;
use std::collections::HashMap;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, RwLock};
use std::time::{Instant, SystemTime};

/// Renders (and world builds) running at once, over all sessions: each
/// holds one blocking thread and shares the render thread pool, so 20
/// clients wait in a queue instead of multiplying threads and frames.
pub const MAX_RENDERS: usize = 2;
/// Sessions kept (each holds at most one accumulated image); the least
/// recently used is dropped, and its render cancelled, past this.
pub const MAX_SESSIONS: usize = 64;
/// Most pixels of accumulated images kept over all sessions (28 bytes each:
/// the colour sum and the cost counts, so about 0.9 GiB). A session that
/// needs room takes it from the least recently used others, whose images are
/// dropped (they start over at their next request).
pub const MAX_ACCUM_PIXELS: u64 = 32 << 20;
/// Worlds kept built (one per scene version and accelerator).
const MAX_WORLDS: usize = 4;

/// The server's state, shared by every request.
pub struct App {
    /// The scene file, canonical.
    pub scene_path: PathBuf,
    /// Every file the scene reads must be inside this folder (canonical).
    pub root: PathBuf,
    /// The scene as last read.
    pub loaded: RwLock<Loaded>,
    worlds: Mutex<Vec<(WorldKey, Arc<World>)>>,
    sessions: Mutex<HashMap<String, Arc<Session>>>,
    /// Bounds the renders running at once ([`MAX_RENDERS`]).
    pub renders: Arc<tokio::sync::Semaphore>,
    /// The render threads (one per core), shared by every render.
    pub pool: rayon::ThreadPool,
    /// Set on shutdown: every render stops at its next tile.
    pub stopping: AtomicBool,
    /// Defaults the page starts from (the command line's).
    pub defaults: serde_json::Value,
    /// The same, for parameters a query leaves out.
    pub defaults_parsed: Defaults,
}

type WorldKey = (u64, String);

/// The scene as last read from disk.
pub struct Loaded {
    /// Bumped at every successful read.
    pub version: u64,
    /// Bumped at every read, good or bad (the page polls it).
    pub generation: u64,
    /// The last scene that parsed.
    pub good: Option<Arc<Scene>>,
    /// Why the latest read failed, ready for the page.
    pub error: Option<serde_json::Value>,
    /// Modification times and sizes of the files the latest read looked at.
    pub stamp: Vec<(PathBuf, Option<(SystemTime, u64)>)>,
}

/// One client's render slot: at most one render at a time; a new request
/// cancels the one running.
pub struct Session {
    current: Mutex<Slot>,
    /// Pixels finished in the pass being rendered.
    pub pass_done: AtomicU64,
    /// Pixels of a whole pass.
    pub pass_total: AtomicU64,
    /// The accumulated image.
    pub accum: Mutex<Option<Accum>>,
    last_used: Mutex<Instant>,
}

/// The running render's cancel flag, and the highest request number the
/// session has seen.
struct Slot {
    flag: Arc<AtomicBool>,
    seq: u32,
}

/// Passes added up so far for one view.
pub struct Accum {
    /// Everything but the target sample count (a change restarts).
    pub key: String,
    /// Image size.
    pub size: (u32, u32),
    /// Sum over passes of (pass image × its samples per pixel).
    pub sum: Vec<Vec3>,
    /// Per-pixel cost of every pass, added up.
    pub cost: Vec<PixelCost>,
    /// Samples per pixel added so far.
    pub spp: u32,
    /// Passes added so far.
    pub passes: u32,
}

impl Session {
    fn new() -> Self {
        Self {
            current: Mutex::new(Slot {
                flag: Arc::new(AtomicBool::new(false)),
                seq: 0,
            }),
            pass_done: AtomicU64::new(0),
            pass_total: AtomicU64::new(0),
            accum: Mutex::new(None),
            last_used: Mutex::new(Instant::now()),
        }
    }

    /// Cancels the session's running render, and returns the flag of a new
    /// one. A request numbered `seq` (the page counts the renders it starts)
    /// is stale if the session has seen a higher number: requests travel on
    /// separate connections and may arrive out of order, and an older one
    /// must not cancel a newer. A stale request gets `None` and cancels
    /// nothing; one without a number always goes ahead.
    pub fn begin(&self, seq: Option<u32>) -> Option<Arc<AtomicBool>> {
        let mut cur = lock(&self.current);
        if let Some(seq) = seq {
            if seq < cur.seq {
                return None;
            }
            cur.seq = seq;
        }
        let flag = Arc::new(AtomicBool::new(false));
        cur.flag.store(true, Ordering::SeqCst);
        cur.flag = flag.clone();
        *lock(&self.last_used) = Instant::now();
        Some(flag)
    }

    /// Cancels whatever the session is rendering.
    pub fn cancel(&self) {
        lock(&self.current).flag.store(true, Ordering::SeqCst);
    }
}

/// Locks a mutex, carrying on past a panicked holder (the data are plain).
pub fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Checks that `p` may be read by the served scene: it resolves (links
/// followed) to a path inside `root`, and that is a regular file. Checked on
/// the metadata, before any open, so that a FIFO or a device is never opened.
pub fn gate(root: &Path, p: &Path) -> io::Result<PathBuf> {
    let c = std::fs::canonicalize(p)?;
    if !c.starts_with(root) {
        return Err(io::Error::new(
            io::ErrorKind::PermissionDenied,
            "it is outside the served root (see --root)",
        ));
    }
    let meta = std::fs::metadata(&c)?;
    if !meta.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "it is not a regular file",
        ));
    }
    Ok(c)
}

fn stamp_of(p: &Path) -> Option<(SystemTime, u64)> {
    let m = std::fs::metadata(p).ok()?;
    Some((m.modified().ok()?, m.len()))
}

impl App {
    /// The state for `scene` served from `root` (both canonical), not yet read.
    pub fn new(scene_path: PathBuf, root: PathBuf, defaults: Defaults) -> io::Result<Self> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(glint::limits::cores())
            .thread_name(|i| format!("glint-serve-render-{i}"))
            .build()
            .map_err(io::Error::other)?;
        Ok(Self {
            scene_path,
            root,
            loaded: RwLock::new(Loaded {
                version: 0,
                generation: 0,
                good: None,
                error: None,
                stamp: Vec::new(),
            }),
            worlds: Mutex::new(Vec::new()),
            sessions: Mutex::new(HashMap::new()),
            renders: Arc::new(tokio::sync::Semaphore::new(MAX_RENDERS)),
            pool,
            stopping: AtomicBool::new(false),
            defaults: defaults.json(),
            defaults_parsed: defaults,
        })
    }

    /// Reads the scene file (and its meshes, through [`gate`]). A good read
    /// replaces the scene; a bad one keeps the last good scene and records
    /// the error. Returns whether the read succeeded.
    pub fn reload(&self) -> bool {
        let root = self.root.clone();
        let gate_fn = move |p: &Path| gate(&root, p);
        let result = gate(&self.root, &self.scene_path)
            .map_err(|e| ParseError {
                file: self.scene_path.clone(),
                line: 0,
                col: 0,
                expected: "a readable scene file".into(),
                found: glint_io_reason(&e),
                source_line: None,
                snippet_offset: 0,
            })
            .and_then(|p| load_scene_gated(&p, &gate_fn));
        let mut stamp = vec![(self.scene_path.clone(), stamp_of(&self.scene_path))];
        let mut l = self.loaded.write().unwrap_or_else(|e| e.into_inner());
        l.generation += 1;
        match result {
            Ok((scene, files)) => {
                stamp.extend(files.into_iter().skip(1).map(|f| {
                    let s = stamp_of(&f);
                    (f, s)
                }));
                l.version += 1;
                l.good = Some(Arc::new(scene));
                l.error = None;
                l.stamp = stamp;
                true
            }
            Err(e) => {
                // Keep watching the meshes of the last good read too.
                stamp.extend(
                    l.stamp
                        .iter()
                        .skip(1)
                        .map(|(f, _)| (f.clone(), stamp_of(f))),
                );
                l.error = Some(self.error_json(&e));
                l.stamp = stamp;
                false
            }
        }
    }

    /// Whether any watched file changed since the last read.
    pub fn changed(&self) -> bool {
        let l = self.loaded.read().unwrap_or_else(|e| e.into_inner());
        l.stamp.iter().any(|(f, s)| stamp_of(f) != *s)
    }

    /// A parse error as the page shows it. Only the served scene's own line
    /// is quoted: for an error inside another file (a mesh), neither its
    /// line nor the token found there is sent.
    pub fn error_json(&self, e: &ParseError) -> serde_json::Value {
        let own = e.file == self.scene_path;
        let file = self.shown_path(&e.file);
        if own {
            let caret = e.col.saturating_sub(e.snippet_offset).max(1);
            let mut rendered = e.render();
            // The path as given is absolute; show it relative to the root.
            rendered = rendered.replace(&e.file.display().to_string(), &file);
            json!({
                "file": file,
                "line": e.line,
                "column": e.col,
                "expected": e.expected,
                "found": e.found,
                "source_line": e.source_line,
                "caret_column": caret,
                "text": glint::limits::bounded_message(&rendered),
            })
        } else {
            let text = format!(
                "{file}:{}:{}: expected {} (the file's contents are not shown)",
                e.line, e.col, e.expected
            );
            json!({
                "file": file,
                "line": e.line,
                "column": e.col,
                "expected": e.expected,
                "found": null,
                "source_line": null,
                "caret_column": null,
                "text": glint::limits::bounded_message(&text),
            })
        }
    }

    /// `p` relative to the root when inside it, else its file name.
    pub fn shown_path(&self, p: &Path) -> String {
        let c = std::fs::canonicalize(p).unwrap_or_else(|_| p.to_owned());
        match c.strip_prefix(&self.root) {
            Ok(rel) => rel.display().to_string(),
            Err(_) => p
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        }
    }

    /// The last good scene and its version.
    pub fn scene(&self) -> Option<(u64, Arc<Scene>)> {
        let l = self.loaded.read().unwrap_or_else(|e| e.into_inner());
        l.good.clone().map(|s| (l.version, s))
    }

    /// The world of scene `version` with accelerator `accel`, built in
    /// world space (the coordinates of the scene file, as `glint raytree`
    /// and `glint traverse` build it), cached.
    pub fn world(&self, version: u64, scene: &Scene, accel: AccelKind) -> Arc<World> {
        let key = (version, accel.to_string());
        if let Some((_, w)) = lock(&self.worlds).iter().find(|(k, _)| *k == key) {
            return w.clone();
        }
        let world = Arc::new(self.pool.install(|| {
            World::build_world_space(
                scene,
                BuildOptions {
                    accel,
                    flatten: true,
                },
            )
        }));
        let mut worlds = lock(&self.worlds);
        worlds.retain(|(k, _)| k.0 == version);
        if worlds.len() >= MAX_WORLDS {
            worlds.remove(0);
        }
        worlds.push((key, world.clone()));
        world
    }

    /// The session named `id`, made if new (dropping the least recently
    /// used one past [`MAX_SESSIONS`]).
    pub fn session(&self, id: &str) -> Arc<Session> {
        let mut s = lock(&self.sessions);
        if let Some(x) = s.get(id) {
            return x.clone();
        }
        if s.len() >= MAX_SESSIONS {
            let oldest = s
                .iter()
                .min_by_key(|(_, v)| *lock(&v.last_used))
                .map(|(k, _)| k.clone());
            if let Some(k) = oldest {
                if let Some(old) = s.remove(&k) {
                    old.cancel();
                }
            }
        }
        let x = Arc::new(Session::new());
        s.insert(id.to_owned(), x.clone());
        x
    }

    /// Drops the accumulated images of the least recently used sessions
    /// other than `me` until `need` more pixels fit in [`MAX_ACCUM_PIXELS`].
    pub fn make_room(&self, me: &Arc<Session>, need: u64) {
        let sessions = lock(&self.sessions);
        let size = |s: &Session| {
            lock(&s.accum)
                .as_ref()
                .map_or(0, |a| u64::from(a.size.0) * u64::from(a.size.1))
        };
        let mut others: Vec<&Arc<Session>> =
            sessions.values().filter(|s| !Arc::ptr_eq(s, me)).collect();
        let mut total: u64 = others.iter().map(|s| size(s)).sum();
        others.sort_by_key(|s| *lock(&s.last_used));
        for s in others {
            if total + need <= MAX_ACCUM_PIXELS {
                break;
            }
            total -= size(s);
            s.cancel();
            *lock(&s.accum) = None;
        }
    }

    /// The session named `id`, if it exists.
    pub fn existing_session(&self, id: &str) -> Option<Arc<Session>> {
        lock(&self.sessions).get(id).cloned()
    }

    /// Cancels every render (shutdown).
    pub fn stop_all(&self) {
        self.stopping.store(true, Ordering::SeqCst);
        for s in lock(&self.sessions).values() {
            s.cancel();
        }
    }
}

/// An I/O error's text without the `(os error N)` tail.
fn glint_io_reason(e: &io::Error) -> String {
    let s = e.to_string();
    match s.find(" (os error") {
        Some(i) => s[..i].to_owned(),
        None => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn app() -> App {
        let dir = std::env::temp_dir();
        let defaults = Defaults {
            size: (4, 4),
            bounces: 5,
            weight: 0.01,
            shadows: false,
            shade_back: false,
            spp: 1,
            accel: "bvh8".into(),
        };
        App::new(dir.join("none.txt"), dir, defaults).expect("the state")
    }

    /// An accumulated image of `w`×`h` pixels as far as the cap counts it
    /// (its size); the buffers stay empty, so the test allocates nothing.
    fn hold(s: &Session, w: u32, h: u32) {
        *lock(&s.accum) = Some(Accum {
            key: String::new(),
            size: (w, h),
            sum: Vec::new(),
            cost: Vec::new(),
            spp: 1,
            passes: 1,
        });
    }

    fn held(s: &Session) -> bool {
        lock(&s.accum).is_some()
    }

    /// Past [`MAX_SESSIONS`] the least recently used session is dropped and
    /// its render cancelled; the others stay.
    #[test]
    fn sessions_past_the_cap_drop_the_least_recently_used() {
        let app = app();
        let first = app.session("s0");
        let flag = first.begin(None).unwrap();
        for i in 1..MAX_SESSIONS {
            app.session(&format!("s{i}")).begin(None);
        }
        assert_eq!(lock(&app.sessions).len(), MAX_SESSIONS);
        assert!(app.existing_session("s0").is_some());
        // s1 is touched again: s0 is now the least recently used.
        app.session("s1").begin(None);
        app.session("one-more").begin(None);
        assert_eq!(lock(&app.sessions).len(), MAX_SESSIONS);
        assert!(app.existing_session("s0").is_none(), "s0 was kept");
        assert!(flag.load(Ordering::SeqCst), "s0's render was not cancelled");
        assert!(app.existing_session("s1").is_some());
        assert!(app.existing_session("one-more").is_some());
    }

    /// A session that needs room drops the least recently used others'
    /// images until the total fits in [`MAX_ACCUM_PIXELS`], and no more.
    #[test]
    fn accumulated_images_stay_within_the_cap() {
        let app = app();
        let side = 2048u32;
        let each = u64::from(side) * u64::from(side);
        let fit = (MAX_ACCUM_PIXELS / each) as usize;
        assert!(fit >= 2, "the cap holds at least two of the largest images");
        let sessions: Vec<_> = (0..fit)
            .map(|i| {
                let s = app.session(&format!("s{i}"));
                let flag = s.begin(None).unwrap();
                hold(&s, side, side);
                (s, flag)
            })
            .collect();
        // Room for a small image: nobody is dropped.
        let me = app.session("me");
        me.begin(None);
        app.make_room(&me, MAX_ACCUM_PIXELS - fit as u64 * each);
        assert!(sessions.iter().all(|(s, _)| held(s)));
        // Room for one more large image: exactly the oldest is dropped and
        // its render cancelled.
        app.make_room(&me, each);
        assert!(!held(&sessions[0].0), "the oldest image was kept");
        assert!(sessions[0].1.load(Ordering::SeqCst));
        assert!(sessions[1..].iter().all(|(s, _)| held(s)));
        assert!(sessions[1..].iter().all(|(_, f)| !f.load(Ordering::SeqCst)));
        // The largest image twice over: the next oldest go too.
        hold(&me, side, side);
        app.make_room(&me, 2 * each);
        let total: u64 = sessions.iter().filter(|(s, _)| held(s)).map(|_| each).sum();
        assert!(total + 2 * each <= MAX_ACCUM_PIXELS, "{total}");
        assert!(held(&sessions[fit - 1].0), "the newest image was dropped");
    }
}
