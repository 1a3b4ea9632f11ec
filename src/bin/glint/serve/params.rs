//! The query parameters of the API, checked: every number in the range the
//! command line accepts ([`glint::limits`]), every name one the command line
//! knows, and a clear message (HTTP 400) otherwise.

use glint::accel::AccelKind;
use glint::integrator::PathSettings;
use glint::limits;
use glint::math::Vec3;
use glint::render::Filter;
use glint::sampler::SamplerKind;
use glint::scene::Camera;
use std::collections::HashMap;
use std::str::FromStr;

/// Largest image side the server renders (a 2048² accumulation is 48 MiB;
/// with [`super::state::MAX_SESSIONS`] sessions the server stays within a
/// few GiB even then).
pub const MAX_SIDE: u32 = 2048;
/// Most grid cells per axis a `grid:NxNxN` accelerator may ask for.
pub const MAX_GRID_RES: u32 = 256;
/// Largest coordinate of a camera given by the page.
const MAX_COORD: f32 = 1e7;

/// Every parameter name any endpoint accepts.
const KNOWN: &[&str] = &[
    "w",
    "h",
    "integrator",
    "accel",
    "shadows",
    "shade_back",
    "bounces",
    "weight",
    "spp",
    "sampler",
    "filter",
    "eye",
    "dir",
    "up",
    "fov",
    "span",
    "x",
    "y",
    "session",
    "pass",
    "seq",
    "overlay",
];

/// Which integrator renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegratorName {
    /// The Whitted ray tree.
    Whitted,
    /// Ambient occlusion.
    Ao,
    /// The path tracer (`glint render --integrator path`).
    Path,
}

/// Everything that decides an image, from the query.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    /// Width and height.
    pub size: (u32, u32),
    /// Integrator.
    pub integrator: IntegratorName,
    /// Accelerator.
    pub accel: AccelKind,
    /// Cast shadow rays.
    pub shadows: bool,
    /// Light back sides.
    pub shade_back: bool,
    /// Reflection/refraction depth.
    pub bounces: u32,
    /// Ray-tree weight cutoff.
    pub weight: f32,
    /// Target samples per pixel.
    pub spp: u32,
    /// Sample layout.
    pub sampler: SamplerKind,
    /// Reconstruction filter.
    pub filter: Filter,
    /// The camera, when the page moved it (else the scene's).
    pub camera: Option<Camera>,
}

/// A parameter error: the message for the 400 response.
pub type Bad = String;

/// The query as a map; unknown names and repeated names are refused.
pub fn query_map(pairs: Vec<(String, String)>) -> Result<HashMap<String, String>, Bad> {
    let mut m = HashMap::new();
    for (k, v) in pairs {
        if !KNOWN.contains(&k.as_str()) {
            return Err(format!("unknown parameter {}", limits::shorten(&k)));
        }
        if m.insert(k.clone(), v).is_some() {
            return Err(format!("parameter {k} given twice"));
        }
    }
    Ok(m)
}

/// A parameter type and its range check: integers within their bounds,
/// floats also finite (`limits`' checks).
trait Ranged: FromStr + Copy {
    fn in_range(name: &str, v: Self, min: Self, max: Self) -> Result<Self, String>;
}

impl Ranged for u32 {
    fn in_range(name: &str, v: u32, min: u32, max: u32) -> Result<u32, String> {
        limits::int_in(name, v, min, max)
    }
}

impl Ranged for f32 {
    fn in_range(name: &str, v: f32, min: f32, max: f32) -> Result<f32, String> {
        limits::finite_in(name, v, min, max)
    }
}

/// Query parameter `name` in `[min, max]`, `default` when absent.
fn number<T: Ranged>(
    q: &HashMap<String, String>,
    name: &str,
    default: T,
    (min, max): (T, T),
) -> Result<T, Bad> {
    match q.get(name) {
        None => Ok(default),
        Some(s) => Ok(T::in_range(name, limits::parse_flag(name, s)?, min, max)?),
    }
}

fn flag(q: &HashMap<String, String>, name: &str, default: bool) -> Result<bool, Bad> {
    match q.get(name).map(String::as_str) {
        None => Ok(default),
        Some("1" | "true" | "on") => Ok(true),
        Some("0" | "false" | "off") => Ok(false),
        Some(s) => Err(format!("{name}: {} is not 0 or 1", limits::shorten(s))),
    }
}

fn named<T: FromStr>(
    q: &HashMap<String, String>,
    name: &str,
    default: &str,
    what: &str,
) -> Result<T, Bad> {
    let s = q.get(name).map_or(default, String::as_str);
    s.parse()
        .map_err(|_| format!("{name}: {} is not {what}", limits::shorten(s)))
}

fn vec3(q: &HashMap<String, String>, name: &str) -> Result<Option<Vec3>, Bad> {
    let Some(s) = q.get(name) else {
        return Ok(None);
    };
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!(
            "{name}: {} is not three numbers x,y,z",
            limits::shorten(s)
        ));
    }
    let mut v = [0.0f32; 3];
    for (i, p) in parts.iter().enumerate() {
        let x: f32 = limits::parse_flag(name, p.trim())?;
        v[i] = limits::finite_in(name, x, -MAX_COORD, MAX_COORD)?;
    }
    Ok(Some(Vec3::from(v)))
}

/// The server's defaults for parameters the query leaves out.
#[derive(Clone, Debug)]
pub struct Defaults {
    /// Image size.
    pub size: (u32, u32),
    /// Bounces.
    pub bounces: u32,
    /// Weight cutoff.
    pub weight: f32,
    /// Shadows.
    pub shadows: bool,
    /// Shade back sides.
    pub shade_back: bool,
    /// Target samples per pixel.
    pub spp: u32,
    /// Accelerator name.
    pub accel: String,
}

impl Defaults {
    /// As JSON, for the page.
    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "w": self.size.0, "h": self.size.1, "bounces": self.bounces,
            "weight": self.weight, "shadows": self.shadows, "shade_back": self.shade_back,
            "spp": self.spp, "accel": self.accel,
            "path_bounces": PathSettings::default().max_bounces,
            "accels": accel_menu(),
            "integrators": ["whitted", "ao", "path"],
        })
    }
}

/// The accelerators the page offers: every name of [`AccelKind::NAMES`]
/// once per accelerator (aliases such as `bvh-sah` for `bvh` left out),
/// the command line's default first.
pub fn accel_menu() -> Vec<String> {
    let mut seen: Vec<AccelKind> = Vec::new();
    let mut names = Vec::new();
    let default = AccelKind::default();
    for n in
        std::iter::once(default.to_string()).chain(AccelKind::NAMES.iter().map(|n| (*n).to_owned()))
    {
        if let Ok(k) = n.parse::<AccelKind>() {
            if !seen.contains(&k) {
                seen.push(k);
                names.push(n);
            }
        }
    }
    names
}

/// The view a query asks for.
pub fn view(q: &HashMap<String, String>, d: &Defaults, scene_camera: &Camera) -> Result<View, Bad> {
    let w = number(q, "w", d.size.0, (1, MAX_SIDE))?;
    let h = number(q, "h", d.size.1, (1, MAX_SIDE))?;
    let integrator = match q.get("integrator").map_or("whitted", String::as_str) {
        "whitted" => IntegratorName::Whitted,
        "ao" => IntegratorName::Ao,
        "path" => IntegratorName::Path,
        s => {
            return Err(format!(
                "integrator: {} is not whitted, ao or path",
                limits::shorten(s)
            ))
        }
    };
    let accel: AccelKind = named(
        q,
        "accel",
        &d.accel,
        "an accelerator (bvh8, none, grid, grid:NxNxN, nested-grid, octree, octree-inner, bvh, bvh-median, bvh-midpoint, bvh-hierarchy)",
    )?;
    // As `glint render`: the path tracer's bounces default to its own.
    let default_bounces = match integrator {
        IntegratorName::Path => PathSettings::default().max_bounces,
        _ => d.bounces,
    };
    if let AccelKind::Grid { res: Some(r) } = accel {
        if r.iter().any(|&n| n > MAX_GRID_RES) {
            return Err(format!(
                "accel: grid:{}x{}x{} has more than {MAX_GRID_RES} cells along an axis",
                r[0], r[1], r[2]
            ));
        }
    }
    let camera = camera(q, scene_camera)?;
    Ok(View {
        size: (w, h),
        integrator,
        accel,
        shadows: flag(q, "shadows", d.shadows)?,
        shade_back: flag(q, "shade_back", d.shade_back)?,
        bounces: number(q, "bounces", default_bounces, (0, limits::MAX_BOUNCES))?,
        weight: number(q, "weight", d.weight, (0.0, f32::MAX))?,
        spp: number(q, "spp", d.spp, (1, limits::MAX_SAMPLES))?,
        sampler: named(
            q,
            "sampler",
            "sobol",
            "a sampler (uniform, random, jittered, sobol)",
        )?,
        filter: named(
            q,
            "filter",
            "box:0.5",
            "a filter (box:R, tent:R, gaussian:SIGMA)",
        )?,
        camera,
    })
}

/// The camera the query gives (`eye`, `dir`, `up`, and `fov` for a
/// perspective scene camera or `span` for an orthographic one), or `None`
/// for the scene's own. Missing parts are the scene camera's.
fn camera(q: &HashMap<String, String>, scene: &Camera) -> Result<Option<Camera>, Bad> {
    if !["eye", "dir", "up", "fov", "span"]
        .iter()
        .any(|k| q.contains_key(*k))
    {
        return Ok(None);
    }
    let (c0, d0, u0) = match *scene {
        Camera::Orthographic {
            center,
            direction,
            up,
            ..
        }
        | Camera::Perspective {
            center,
            direction,
            up,
            ..
        } => (center, direction, up),
    };
    let center = vec3(q, "eye")?.map_or(c0, |v| v.as_dvec3());
    let direction = vec3(q, "dir")?.unwrap_or(d0);
    let up = vec3(q, "up")?.unwrap_or(u0);
    let (d, u) = (direction.as_dvec3(), up.as_dvec3());
    if d.length() < 1e-9 {
        return Err("dir: the view direction must not be zero".into());
    }
    if d.normalize().cross(u).length() < 1e-6 * u.length().max(1e-30) || u.length() < 1e-9 {
        return Err("up: the up vector must be non-zero and not parallel to dir".into());
    }
    Ok(Some(match *scene {
        Camera::Perspective { angle_deg, .. } => Camera::Perspective {
            center,
            direction,
            up,
            angle_deg: number(q, "fov", angle_deg, (0.1, 179.0))?,
        },
        Camera::Orthographic { size, .. } => Camera::Orthographic {
            center,
            direction,
            up,
            size: number(q, "span", size, (1e-6, MAX_COORD))?,
        },
    }))
}

/// A pixel `x`, `y` inside a `w`×`h` image.
pub fn pixel(q: &HashMap<String, String>, (w, h): (u32, u32)) -> Result<(u32, u32), Bad> {
    let (Some(_), Some(_)) = (q.get("x"), q.get("y")) else {
        return Err("give the pixel as x and y".into());
    };
    let x = number(q, "x", 0, (0, w - 1))?;
    let y = number(q, "y", 0, (0, h - 1))?;
    Ok((x, y))
}

/// The session id: 1 to 64 letters, digits, `-` or `_`.
pub fn session(q: &HashMap<String, String>) -> Result<String, Bad> {
    let s = q.get("session").ok_or("give a session id (session=...)")?;
    if s.is_empty()
        || s.len() > 64
        || !s
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    {
        return Err(format!(
            "session: {} is not 1 to 64 letters, digits, - or _",
            limits::shorten(s)
        ));
    }
    Ok(s.clone())
}

/// The pass the page expects next (0 to start over).
pub fn pass(q: &HashMap<String, String>) -> Result<u32, Bad> {
    number(q, "pass", 0, (0, limits::MAX_SAMPLES))
}

/// The request's number among the session's renders (`seq=N`), if given:
/// a request never cancels one with a higher number.
pub fn seq(q: &HashMap<String, String>) -> Result<Option<u32>, Bad> {
    q.get("seq")
        .map(|_| number(q, "seq", 0, (0, u32::MAX)))
        .transpose()
}
