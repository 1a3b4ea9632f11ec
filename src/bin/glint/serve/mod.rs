//! `glint serve SCENE [--port P] [--root DIR]`: the scene live in a browser
//! (`docs/serve.md`). An HTTP server on 127.0.0.1 only (axum on tokio): the
//! page, its script and style are compiled into the binary; the API renders
//! progressively, traces a clicked pixel's ray tree, records an
//! accelerator's walk, and watches the scene file.
//!
//! Bounds: renders run at most [`state::MAX_RENDERS`] at a time on one
//! shared pool of render threads (one per core), one per session (a new
//! request cancels the session's running render), sessions are capped at
//! [`state::MAX_SESSIONS`]; request bodies over [`MAX_BODY`] bytes are
//! refused; every number is checked against the command line's limits.

mod api;
pub mod params;
mod render;
mod state;

use axum::extract::Request;
use axum::http::{header, HeaderValue, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use params::Defaults;
use state::App;
use std::io::Write as _;
use std::net::{Ipv4Addr, SocketAddr};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

/// The port `glint serve` listens on unless told otherwise.
pub const DEFAULT_PORT: u16 = 8837;
/// Largest request body accepted (every endpoint is a GET: none needs one).
pub const MAX_BODY: u64 = 4096;
/// How often the scene file and its meshes are looked at for changes.
const WATCH_EVERY: Duration = Duration::from_millis(250);

const INDEX_HTML: &str = include_str!("page/index.html");
const APP_JS: &str = include_str!("page/app.js");
const STYLE_CSS: &str = include_str!("page/style.css");

/// Arguments of `glint serve`.
#[derive(clap::Args)]
pub struct ServeArgs {
    /// Scene file (MIT 6.837 format).
    pub scene: PathBuf,
    /// Port on 127.0.0.1 (0: any free port; the address is printed). Default: 8837, or any free port when 8837 is taken.
    #[arg(long)]
    pub port: Option<u16>,
    /// Folder every file the scene reads must be inside (default: the scene's folder).
    #[arg(long, value_name = "DIR")]
    pub root: Option<PathBuf>,
    /// Image size the page starts with.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [400, 400])]
    pub size: Vec<u32>,
    /// Maximum reflection/refraction bounces the page starts with.
    #[arg(long, default_value_t = 5)]
    pub bounces: u32,
    /// Ray-tree weight cutoff the page starts with.
    #[arg(long, default_value_t = 0.01)]
    pub weight: f32,
    /// Start with shadows on.
    #[arg(long)]
    pub shadows: bool,
    /// Start with back sides lit.
    #[arg(long)]
    pub shade_back: bool,
    /// Samples per pixel the progressive render refines to.
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    /// Accelerator the page starts with (the same names and default as `glint render --accel`).
    #[arg(long, default_value = "bvh8")]
    pub accel: glint::accel::AccelKind,
}

/// Runs `glint serve` until Ctrl-C; a refused request is a usage error.
pub fn run(a: ServeArgs) -> Result<(), glint::job::JobError> {
    let defaults = Defaults {
        size: (a.size[0], a.size[1]),
        bounces: a.bounces,
        weight: a.weight,
        shadows: a.shadows,
        shade_back: a.shade_back,
        spp: a.spp,
        accel: a.accel.to_string(),
    };
    serve(&a.scene, a.root.as_deref(), a.port, defaults, "glint")
        .map_err(glint::job::JobError::Usage)
}

/// Checks the defaults as a query would be checked.
fn check_defaults(d: &Defaults) -> Result<(), String> {
    use glint::limits;
    limits::int_in("--size", d.size.0, 1, params::MAX_SIDE)?;
    limits::int_in("--size", d.size.1, 1, params::MAX_SIDE)?;
    limits::int_in("--bounces", d.bounces, 0, limits::MAX_BOUNCES)?;
    limits::finite_in("--weight", d.weight, 0.0, f32::MAX)?;
    limits::int_in("--spp", d.spp, 1, limits::MAX_SAMPLES)?;
    d.accel
        .parse::<glint::accel::AccelKind>()
        .map_err(|e| format!("--accel: {e}"))?;
    Ok(())
}

/// Serves `scene` until Ctrl-C (or SIGTERM); `program` names the command
/// in messages. The address is printed on stdout as soon as it listens.
/// Without a `port`, [`DEFAULT_PORT`] if it is free, else any free port.
pub fn serve(
    scene: &Path,
    root: Option<&Path>,
    port: Option<u16>,
    defaults: Defaults,
    program: &'static str,
) -> Result<(), String> {
    check_defaults(&defaults)?;
    let scene_c = std::fs::canonicalize(scene).map_err(|e| format!("{}: {e}", scene.display()))?;
    let root = match root {
        Some(r) => r.to_owned(),
        None => scene_c.parent().unwrap_or(Path::new("/")).to_owned(),
    };
    let root =
        std::fs::canonicalize(&root).map_err(|e| format!("--root {}: {e}", root.display()))?;
    if !root.is_dir() {
        return Err(format!("--root {}: not a folder", root.display()));
    }
    state::gate(&root, &scene_c).map_err(|e| format!("{}: {e}", scene.display()))?;
    let app = Arc::new(App::new(scene_c, root, defaults).map_err(|e| e.to_string())?);
    if !app.reload() {
        let l = app.loaded.read().unwrap_or_else(|e| e.into_inner());
        if let Some(e) = &l.error {
            eprintln!(
                "{program}: the scene does not parse yet (the page shows why; fix and save it):\n{}",
                e["text"].as_str().unwrap_or_default()
            );
        }
    }
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .max_blocking_threads(state::MAX_RENDERS + 4)
        .enable_all()
        .build()
        .map_err(|e| format!("could not start the server's threads: {e}"))?;
    rt.block_on(async move {
        let addr = SocketAddr::from((Ipv4Addr::LOCALHOST, port.unwrap_or(DEFAULT_PORT)));
        let listener = match tokio::net::TcpListener::bind(addr).await {
            Ok(l) => l,
            Err(_) if port.is_none() => {
                tokio::net::TcpListener::bind(SocketAddr::from((Ipv4Addr::LOCALHOST, 0)))
                    .await
                    .map_err(|e| format!("cannot listen on 127.0.0.1: {e}"))?
            }
            Err(e) => return Err(format!("cannot listen on {addr}: {e}")),
        };
        let local = listener.local_addr().map_err(|e| e.to_string())?;
        println!(
            "{program} serve: http://{local}/  ({})",
            app.scene_path.display()
        );
        let _ = std::io::stdout().flush();
        tokio::spawn(watch(app.clone()));
        let stop_app = app.clone();
        axum::serve(listener, router(app))
            .with_graceful_shutdown(async move {
                shutdown_signal().await;
                eprintln!("{program} serve: stopping");
                stop_app.stop_all();
            })
            .await
            .map_err(|e| e.to_string())
    })?;
    rt.shutdown_timeout(Duration::from_secs(5));
    Ok(())
}

async fn shutdown_signal() {
    let ctrl_c = tokio::signal::ctrl_c();
    #[cfg(unix)]
    {
        let mut term =
            match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
                Ok(s) => s,
                Err(_) => {
                    let _ = ctrl_c.await;
                    return;
                }
            };
        tokio::select! {
            _ = ctrl_c => {},
            _ = term.recv() => {},
        }
    }
    #[cfg(not(unix))]
    {
        let _ = ctrl_c.await;
    }
}

/// Polls the scene file and its meshes; reloads when one changed.
async fn watch(app: Arc<App>) {
    let mut tick = tokio::time::interval(WATCH_EVERY);
    loop {
        tick.tick().await;
        if app.stopping.load(std::sync::atomic::Ordering::SeqCst) {
            return;
        }
        let a = app.clone();
        let _ = tokio::task::spawn_blocking(move || {
            if a.changed() {
                a.reload();
            }
        })
        .await;
    }
}

fn router(app: Arc<App>) -> Router {
    Router::new()
        .route(
            "/",
            get(|| async { page(INDEX_HTML, "text/html; charset=utf-8") }),
        )
        .route(
            "/app.js",
            get(|| async { page(APP_JS, "text/javascript; charset=utf-8") }),
        )
        .route(
            "/style.css",
            get(|| async { page(STYLE_CSS, "text/css; charset=utf-8") }),
        )
        .route("/favicon.ico", get(|| async { StatusCode::NO_CONTENT }))
        .route("/api/status", get(api::status))
        .route("/api/scene", get(api::scene))
        .route("/api/render", get(api::render))
        .route("/api/progress", get(api::progress))
        .route("/api/cost", get(api::cost_map))
        .route("/api/raytree", get(api::raytree))
        .route("/api/traversal", get(api::traversal))
        .route("/api/grid", get(api::grid_cells))
        .fallback(|| async { api::ApiError(StatusCode::NOT_FOUND, "no such page".into()) })
        .layer(middleware::from_fn(bounded_body))
        .layer(axum::extract::DefaultBodyLimit::max(MAX_BODY as usize))
        .with_state(app)
}

fn page(body: &'static str, kind: &'static str) -> Response {
    let mut r = body.into_response();
    r.headers_mut()
        .insert(header::CONTENT_TYPE, HeaderValue::from_static(kind));
    r
}

/// Refuses a request announcing a body over [`MAX_BODY`] bytes, or one of
/// unknown length, before anything reads it.
async fn bounded_body(req: Request, next: Next) -> Response {
    let h = req.headers();
    let len = h
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse::<u64>().ok());
    if h.contains_key(header::TRANSFER_ENCODING) || len.is_some_and(|n| n > MAX_BODY) {
        return api::ApiError(
            StatusCode::PAYLOAD_TOO_LARGE,
            format!("request bodies are limited to {MAX_BODY} bytes"),
        )
        .into_response();
    }
    next.run(req).await
}
