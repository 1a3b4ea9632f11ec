//! The HTTP endpoints. Everything is a GET with its parameters in the query
//! (see `docs/serve.md`); a bad parameter is a 400 with a one-line message.

use super::params::{self, View};
use super::render;
use super::state::{lock, Accum, App};
use axum::extract::{Query, State};
use axum::http::{header, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};
use glint::math::Vec3;
use glint::render::{Control, PixelCost, PixelOffset};
use glint::scene::{Camera, Scene};
use glint::viz::{cost, grid, raytree, traversal};
use serde_json::{json, Value};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Most triangles `/api/scene` sends for the 3-D view (more are thinned
/// evenly, and the answer says how many were left out).
const MAX_VIEW_TRIANGLES: usize = 60_000;
/// Most occupied grid cells `/api/grid` sends.
const MAX_GRID_CELLS: usize = 3_000;

/// An error answer: a status and a one-line message.
pub struct ApiError(pub StatusCode, pub String);

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let mut r = (self.0, glint::limits::bounded_message(&self.1) + "\n").into_response();
        r.headers_mut().insert(
            header::CONTENT_TYPE,
            HeaderValue::from_static("text/plain; charset=utf-8"),
        );
        r
    }
}

impl From<params::Bad> for ApiError {
    fn from(msg: params::Bad) -> Self {
        ApiError(StatusCode::BAD_REQUEST, msg)
    }
}

type Q = Query<Vec<(String, String)>>;
type Answer = Result<Response, ApiError>;

fn internal(e: impl std::fmt::Display) -> ApiError {
    ApiError(StatusCode::INTERNAL_SERVER_ERROR, e.to_string())
}

fn no_scene(app: &App) -> ApiError {
    let l = app.loaded.read().unwrap_or_else(|e| e.into_inner());
    let why = l
        .error
        .as_ref()
        .and_then(|e| e["text"].as_str().map(str::to_owned))
        .unwrap_or_default();
    ApiError(
        StatusCode::CONFLICT,
        format!("the scene has not loaded yet: {why}"),
    )
}

/// The query, the scene version, the last good scene, and the view the query asks for.
type Setup = (HashMap<String, String>, u64, Arc<Scene>, View);

/// The query, the last good scene, and the view the query asks for.
fn setup(app: &App, q: Vec<(String, String)>) -> Result<Setup, ApiError> {
    let q = params::query_map(q)?;
    let (version, scene) = app.scene().ok_or_else(|| no_scene(app))?;
    let view = params::view(&q, &app.defaults_parsed, &scene.camera)?;
    Ok((q, version, scene, view))
}

/// Runs `f` on a blocking thread once a render permit is free.
async fn blocking<T: Send + 'static>(
    app: &Arc<App>,
    f: impl FnOnce(&App) -> Result<T, ApiError> + Send + 'static,
) -> Result<T, ApiError> {
    let permit = app.renders.clone().acquire_owned().await.map_err(|_| {
        ApiError(
            StatusCode::SERVICE_UNAVAILABLE,
            "the server is stopping".into(),
        )
    })?;
    let app = app.clone();
    let out = tokio::task::spawn_blocking(move || {
        let _permit = permit;
        f(&app)
    })
    .await
    .map_err(internal)?;
    out
}

fn json_answer(v: Value) -> Response {
    let mut r = axum::Json(v).into_response();
    r.headers_mut()
        .insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    r
}

fn png_answer(bytes: Vec<u8>, headers: &[(&'static str, String)]) -> Response {
    let mut r = bytes.into_response();
    let h = r.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static("image/png"));
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    for (k, v) in headers {
        if let Ok(v) = HeaderValue::from_str(v) {
            h.insert(*k, v);
        }
    }
    r
}

/// `GET /api/status`: the scene's version and its latest parse error.
pub async fn status(State(app): State<Arc<App>>) -> Response {
    let l = app.loaded.read().unwrap_or_else(|e| e.into_inner());
    json_answer(json!({
        "scene": app.shown_path(&app.scene_path),
        "version": l.version,
        "generation": l.generation,
        "loaded": l.good.is_some(),
        "error": l.error,
        "defaults": app.defaults,
    }))
}

fn v3(v: Vec3) -> Value {
    json!([v.x, v.y, v.z])
}

fn camera_json(c: &Camera) -> Value {
    match *c {
        Camera::Perspective {
            center,
            direction,
            up,
            angle_deg,
        } => {
            json!({"kind": "perspective", "eye": v3(center.as_vec3()), "dir": v3(direction), "up": v3(up), "fov": angle_deg})
        }
        Camera::Orthographic {
            center,
            direction,
            up,
            size,
        } => {
            json!({"kind": "orthographic", "eye": v3(center.as_vec3()), "dir": v3(direction), "up": v3(up), "span": size})
        }
    }
}

/// `GET /api/scene`: the scene's camera, bounds and geometry for the 3-D
/// view (triangles, spheres as centre and radius, planes), in world space.
pub async fn scene(State(app): State<Arc<App>>, Query(q): Q) -> Answer {
    let (_, version, scene, view) = setup(&app, q)?;
    let v = blocking(&app, move |app| {
        let world = app.world(version, &scene, view.accel);
        let mut tris = Vec::new();
        let mut spheres = Vec::new();
        let mut planes = Vec::new();
        let mut others = Vec::new();
        for p in world.prims() {
            match &p.shape {
                glint::shape::Shape::Triangle(t) => tris.push(t.v),
                glint::shape::Shape::Sphere(s) => spheres.push(json!([s.center.x, s.center.y, s.center.z, s.radius])),
                glint::shape::Shape::Plane(pl) => planes.push(json!([pl.normal.x, pl.normal.y, pl.normal.z, pl.offset])),
                other => {
                    let b = other.bounds();
                    others.push(json!([v3(b.min), v3(b.max)]));
                }
            }
        }
        let total = tris.len();
        let stride = total.div_ceil(MAX_VIEW_TRIANGLES).max(1);
        let flat: Vec<f32> = tris
            .iter()
            .step_by(stride)
            .flat_map(|v| v.iter().flat_map(|p| p.to_array()))
            .collect();
        let b = world.bounds();
        Ok(json!({
            "version": version,
            "camera": camera_json(&scene.camera),
            "bounds": if b.is_empty() { Value::Null } else { json!({"min": v3(b.min), "max": v3(b.max)}) },
            "triangles": flat,
            "triangles_total": total,
            "triangles_shown": total.div_ceil(stride),
            "spheres": spheres,
            "planes": planes,
            "boxes": others,
        }))
    })
    .await?;
    Ok(json_answer(v))
}

/// Sets the flag when dropped: a request whose client went away cancels
/// its render.
struct CancelOnDrop(Arc<AtomicBool>);

impl Drop for CancelOnDrop {
    fn drop(&mut self) {
        self.0.store(true, Ordering::SeqCst);
    }
}

/// `GET /api/render?session=S&pass=K&...`: the next pass of the session's
/// progressive render, added to the passes before it, as PNG. Pass 0, a
/// different view or a different scene version starts over; the headers
/// say how far the image is (`X-Glint-Spp` of `X-Glint-Target`,
/// `X-Glint-Pass`, `X-Glint-Done`). A newer request of the same session
/// cancels this one (409).
pub async fn render(State(app): State<Arc<App>>, Query(q): Q) -> Answer {
    let (q, version, scene, view) = setup(&app, q)?;
    let sid = params::session(&q)?;
    let want = params::pass(&q)?;
    let seq = params::seq(&q)?;
    let session = app.session(&sid);
    let superseded = || {
        ApiError(
            StatusCode::CONFLICT,
            "superseded by a newer request of this session".into(),
        )
    };
    let flag = session.begin(seq).ok_or_else(superseded)?;
    let guard = CancelOnDrop(flag.clone());
    let target = view.spp;
    let out = blocking(&app, move |app| {
        if flag.load(Ordering::SeqCst) {
            return Err(superseded());
        }
        let mut key_view = view.clone();
        key_view.spp = 0;
        let key = format!("{version}|{key_view:?}");
        let (done, passes) = {
            let mut acc = lock(&session.accum);
            let fresh = want == 0
                || acc
                    .as_ref()
                    .is_none_or(|a| a.key != key || a.passes != want);
            if fresh {
                let n = (view.size.0 * view.size.1) as usize;
                *acc = None;
                drop(acc);
                app.make_room(&session, n as u64);
                acc = lock(&session.accum);
                *acc = Some(Accum {
                    key: key.clone(),
                    size: view.size,
                    sum: vec![Vec3::ZERO; n],
                    cost: vec![PixelCost::default(); n],
                    spp: 0,
                    passes: 0,
                });
            }
            let a = acc.as_ref().expect("set above");
            (a.spp, a.passes)
        };
        let started = std::time::Instant::now();
        let n = render::pass_spp(view.sampler, done, view.spp);
        if n > 0 {
            let world = app.world(version, &scene, view.accel);
            let total = u64::from(view.size.0) * u64::from(view.size.1);
            session.pass_total.store(total, Ordering::Relaxed);
            session.pass_done.store(0, Ordering::Relaxed);
            let tick = |p: u64| {
                session.pass_done.fetch_add(p, Ordering::Relaxed);
            };
            let control = Control {
                cancel: Some(&flag),
                on_progress: Some(&tick),
            };
            let r = app
                .pool
                .install(|| render::pass(&world, &scene, &view, n, u64::from(passes), control));
            if flag.load(Ordering::SeqCst) || !r.frame.is_complete() {
                return Err(superseded());
            }
            let mut acc = lock(&session.accum);
            let a = acc
                .as_mut()
                .filter(|a| a.key == key && a.passes == passes)
                .ok_or_else(superseded)?;
            for (s, c) in a.sum.iter_mut().zip(&r.frame.color) {
                *s += *c * n as f32;
            }
            for (s, c) in a.cost.iter_mut().zip(&r.frame.cost) {
                s.tests += c.tests;
                s.nodes += c.nodes;
            }
            a.spp += n;
            a.passes += 1;
        }
        let acc = lock(&session.accum);
        let a = acc.as_ref().ok_or_else(superseded)?;
        let scale = 1.0 / a.spp.max(1) as f32;
        let pixels: Vec<Vec3> = a.sum.iter().map(|s| *s * scale).collect();
        let png = render::png(a.size.0, a.size.1, &pixels).map_err(internal)?;
        Ok((png, a.spp, a.passes, started.elapsed().as_secs_f64() * 1e3))
    })
    .await;
    drop(guard);
    let (png, spp, passes, ms) = out?;
    Ok(png_answer(
        png,
        &[
            ("x-glint-spp", spp.to_string()),
            ("x-glint-target", target.to_string()),
            ("x-glint-pass", passes.to_string()),
            ("x-glint-done", (spp >= target).to_string()),
            ("x-glint-version", version.to_string()),
            ("x-glint-ms", format!("{ms:.1}")),
        ],
    ))
}

/// `GET /api/progress?session=S`: how far the session's current pass is.
pub async fn progress(State(app): State<Arc<App>>, Query(q): Q) -> Answer {
    let q = params::query_map(q)?;
    let sid = params::session(&q)?;
    let Some(s) = app.existing_session(&sid) else {
        return Err(ApiError(StatusCode::NOT_FOUND, format!("no session {sid}")));
    };
    let (spp, passes) = lock(&s.accum)
        .as_ref()
        .map_or((0, 0), |a| (a.spp, a.passes));
    Ok(json_answer(json!({
        "pass_done": s.pass_done.load(Ordering::Relaxed),
        "pass_total": s.pass_total.load(Ordering::Relaxed),
        "spp": spp,
        "passes": passes,
    })))
}

/// `GET /api/cost?session=S`: the per-pixel cost of the session's image so
/// far (every pass's rays), as `glint render --cost-image` draws it:
/// intersection tests left, nodes or cells visited right, with scale bars.
pub async fn cost_map(State(app): State<Arc<App>>, Query(q): Q) -> Answer {
    let q = params::query_map(q)?;
    let sid = params::session(&q)?;
    let Some(s) = app.existing_session(&sid) else {
        return Err(ApiError(StatusCode::NOT_FOUND, format!("no session {sid}")));
    };
    let frame = {
        let acc = lock(&s.accum);
        let Some(a) = acc.as_ref().filter(|a| a.spp > 0) else {
            return Err(ApiError(
                StatusCode::NOT_FOUND,
                "nothing rendered yet in this session".into(),
            ));
        };
        let mut f = glint::render::Frame::new(a.size.0, a.size.1);
        f.cost.clone_from(&a.cost);
        f
    };
    let c = cost::image(&frame);
    let (t, n) = cost::totals(&frame);
    let png = render::png(c.width, c.height, &c.pixels).map_err(internal)?;
    Ok(png_answer(
        png,
        &[
            ("x-glint-tests", t.to_string()),
            ("x-glint-nodes", n.to_string()),
        ],
    ))
}

fn xy(p: Option<(glint::math::Vec2, glint::math::Vec2)>, h: u32) -> Value {
    // Pixel coordinates with y down from the top, as the page's canvas has them.
    p.map_or(Value::Null, |(a, b)| {
        json!([a.x, h as f32 - a.y, b.x, h as f32 - b.y])
    })
}

/// `GET /api/raytree?x=X&y=Y&...`: every ray pixel (X, Y) spawns, the JSON
/// of `glint raytree -o tree.json` for the same settings. With `overlay=1`:
/// `{"tree": ..., "overlay": [...]}`, the overlay holding each ray's segment
/// projected into the image (`[x0, y0, x1, y1]`, y down, or null).
pub async fn raytree(State(app): State<Arc<App>>, Query(q): Q) -> Answer {
    let (q, version, scene, view) = setup(&app, q)?;
    let (x, y) = params::pixel(&q, view.size)?;
    let overlay = q.get("overlay").is_some_and(|v| v == "1");
    let v = blocking(&app, move |app| {
        let world = app.world(version, &scene, view.accel);
        let cam = render::camera(&world, &scene, &view);
        let integ = render::whitted(&scene, &view);
        let tree = raytree::record(&world, &cam, &integ, view.size, (x, y), PixelOffset::CENTER);
        let j = tree.to_json();
        Ok(if overlay {
            let o: Vec<Value> = tree
                .projected(&cam, view.size)
                .into_iter()
                .map(|p| xy(p, view.size.1))
                .collect();
            json!({"tree": j, "overlay": o})
        } else {
            j
        })
    })
    .await?;
    Ok(json_answer(v))
}

fn segments_json(segs: &[((Vec3, Vec3), Vec3)]) -> Vec<Value> {
    segs.iter()
        .map(|((a, b), c)| json!([a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z]))
        .collect()
}

/// `GET /api/traversal?x=X&y=Y&accel=A&...`: the cells, leaves or boxes the
/// accelerator's search looked at for pixel (X, Y)'s eye ray (what `glint
/// traverse` draws), as 3-D segments with colours and their projection.
pub async fn traversal(State(app): State<Arc<App>>, Query(q): Q) -> Answer {
    let (q, version, scene, view) = setup(&app, q)?;
    let (x, y) = params::pixel(&q, view.size)?;
    let v = blocking(&app, move |app| {
        let world = app.world(version, &scene, view.accel);
        let cam = render::camera(&world, &scene, &view);
        let structure = traversal::Structure::build(&world, view.accel).ok_or_else(|| {
            let why = match view.accel {
                glint::accel::AccelKind::None => "brute force walks nothing",
                _ => "the 8-wide BVH's loops record no walk",
            };
            ApiError(
                StatusCode::BAD_REQUEST,
                format!(
                    "accel {}: {why}; choose grid, nested-grid, octree, octree-inner or a binary bvh to see one",
                    view.accel
                ),
            )
        })?;
        let bvh = matches!(structure, traversal::Structure::Bvh(_));
        let (w, h) = view.size;
        let ray = cam.ray(glint::render::screen_point(x, h - 1 - y, PixelOffset::CENTER.0, w, h));
        let (hit, visits) = structure.trace(&world, &ray, cam.tmin());
        let segs = traversal::segments(&ray, hit, &visits, bvh);
        let overlay: Vec<Value> = traversal::project(&cam, &segs, view.size)
            .into_iter()
            .map(|p| xy(p, h))
            .collect();
        Ok(json!({
            "accel": view.accel.to_string(),
            "pixel": [x, y],
            "hit_t": hit.map(|h| h.t),
            "visits": visits.len(),
            "entered": visits.iter().filter(|v| v.entered).count(),
            "faces": visits.iter().filter(|v| v.face.is_some()).count(),
            "segments": segments_json(&segs),
            "overlay": overlay,
        }))
    })
    .await?;
    Ok(json_answer(v))
}

/// `GET /api/grid?accel=grid[:NxNxN]&...`: the occupied cells of the grid
/// the renderer builds (coloured by primitive count, as `-visualize_grid`),
/// as 3-D box edges and their projection.
pub async fn grid_cells(State(app): State<Arc<App>>, Query(q): Q) -> Answer {
    let (_, version, scene, view) = setup(&app, q)?;
    let v = blocking(&app, move |app| {
        let world = app.world(version, &scene, view.accel);
        let cam = render::camera(&world, &scene, &view);
        let res = match view.accel {
            glint::accel::AccelKind::Grid { res } => res,
            _ => None,
        };
        let vox = grid::voxelize(&world, res);
        let occupied = vox.occupied();
        let max = vox.max_count();
        let mut segs = Vec::new();
        for c in occupied.iter().take(MAX_GRID_CELLS) {
            let n = vox.count(c.map(i64::from));
            let color = grid::count_color(n, max);
            let b = vox.lattice.cell_bounds(*c);
            segs.extend(traversal::box_edges(&b).into_iter().map(|e| (e, color)));
        }
        let overlay: Vec<Value> = traversal::project(&cam, &segs, view.size)
            .into_iter()
            .map(|p| xy(p, view.size.1))
            .collect();
        Ok(json!({
            "res": vox.lattice.res,
            "occupied": occupied.len(),
            "shown": occupied.len().min(MAX_GRID_CELLS),
            "max_count": max,
            "segments": segments_json(&segs),
            "overlay": overlay,
        }))
    })
    .await?;
    Ok(json_answer(v))
}
