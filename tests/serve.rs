//! `glint serve` over HTTP: the binary as a user starts it, on a free port,
//! spoken to with plain HTTP/1.1 over a TCP socket.

use crate::common;
use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// How long a wait may last before the test calls it a hang.
const HANG: Duration = Duration::from_secs(120);

/// Fails with `what` once `since` is [`HANG`] ago: a guard against a server
/// that never answers or never stops, not a speed test (the limit is far
/// beyond any wait on a loaded machine; speed is measured by benchmarks).
fn no_hang(since: Instant, what: &str) {
    assert!(
        since.elapsed() < HANG,
        "{what} (no progress in {HANG:?}: a hang)"
    );
}

/// A running server, stopped (its own process only) when dropped.
struct Server {
    child: Child,
    addr: String,
}

impl Server {
    fn start(bin: &str, args: &[&str]) -> Server {
        let mut child = Command::new(bin)
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start the server");
        let mut line = String::new();
        BufReader::new(child.stdout.take().expect("stdout"))
            .read_line(&mut line)
            .expect("the address line");
        let addr = line
            .split("http://")
            .nth(1)
            .and_then(|s| s.split('/').next())
            .unwrap_or_else(|| panic!("no address in {line:?}"))
            .to_owned();
        assert!(addr.starts_with("127.0.0.1:"), "{addr}");
        Server { child, addr }
    }

    fn glint(scene: &Path, extra: &[&str]) -> Server {
        let mut args = vec!["serve", scene.to_str().unwrap(), "--port", "0"];
        args.extend_from_slice(extra);
        Server::start(env!("CARGO_BIN_EXE_glint"), &args)
    }

    fn get(&self, path: &str) -> Reply {
        request(
            &self.addr,
            &format!("GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"),
        )
    }

    fn json(&self, path: &str) -> Value {
        let r = self.get(path);
        assert_eq!(r.status, 200, "{path}: {}", r.text());
        serde_json::from_slice(&r.body).unwrap_or_else(|e| panic!("{path}: {e}"))
    }

    /// Polls `/api/status` until `f` holds (see [`no_hang`]).
    fn wait_status(&self, f: impl Fn(&Value) -> bool) -> Value {
        let t = Instant::now();
        loop {
            let s = self.json("/api/status");
            if f(&s) {
                return s;
            }
            no_hang(t, &format!("status never changed: {s}"));
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

struct Reply {
    status: u16,
    headers: Vec<(String, String)>,
    body: Vec<u8>,
}

impl Reply {
    fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).into_owned()
    }
    fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }
    fn png(&self) -> image::RgbImage {
        assert_eq!(self.status, 200, "{}", self.text());
        assert_eq!(self.header("content-type"), Some("image/png"));
        image::load_from_memory(&self.body)
            .expect("a PNG")
            .to_rgb8()
    }
}

/// Sends `raw` and reads the whole answer (the server closes it).
fn request(addr: &str, raw: &str) -> Reply {
    let mut s = TcpStream::connect(addr).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
    s.write_all(raw.as_bytes()).unwrap();
    let mut buf = Vec::new();
    s.read_to_end(&mut buf).expect("read the answer");
    let split = buf
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("a header block");
    let head = String::from_utf8_lossy(&buf[..split]).into_owned();
    let mut lines = head.split("\r\n");
    let status: u16 = lines
        .next()
        .unwrap()
        .split(' ')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    let headers: Vec<(String, String)> = lines
        .filter_map(|l| l.split_once(':'))
        .map(|(k, v)| (k.trim().to_owned(), v.trim().to_owned()))
        .collect();
    let mut body = buf[split + 4..].to_vec();
    if headers
        .iter()
        .any(|(k, v)| k.eq_ignore_ascii_case("transfer-encoding") && v.contains("chunked"))
    {
        body = dechunk(&body);
    }
    Reply {
        status,
        headers,
        body,
    }
}

fn dechunk(mut b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let nl = b.windows(2).position(|w| w == b"\r\n").unwrap();
        let n = usize::from_str_radix(std::str::from_utf8(&b[..nl]).unwrap().trim(), 16).unwrap();
        if n == 0 {
            return out;
        }
        out.extend_from_slice(&b[nl + 2..nl + 2 + n]);
        b = &b[nl + 4 + n..];
    }
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("glint-serve-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const SMALL: &str = "w=48&h=32";

/// Every endpoint answers with what it documents.
#[test]
fn every_endpoint_answers() {
    let s = Server::glint(&common::own_scene("whitted.txt"), &[]);
    let page = s.get("/");
    assert_eq!(page.status, 200);
    assert!(page.text().contains("<canvas id=\"image\""));
    assert!(s.get("/app.js").text().contains("/api/render"));
    assert!(s.get("/style.css").text().contains("#overlay"));
    assert_eq!(s.get("/no/such/page").status, 404);

    let st = s.json("/api/status");
    assert_eq!(st["loaded"], true);
    assert_eq!(st["scene"], "whitted.txt");
    assert!(st["error"].is_null());

    let sc = s.json(&format!("/api/scene?{SMALL}"));
    let n = sc["triangles"].as_array().unwrap().len() + sc["spheres"].as_array().unwrap().len();
    assert!(n > 0, "{sc}");
    assert_eq!(sc["camera"]["kind"], "perspective");

    // Progressive: pass 0 is 1 spp, pass 1 adds 1, pass 2 adds 2.
    let q = format!("/api/render?{SMALL}&spp=4&session=t1");
    let mut spp = Vec::new();
    for pass in 0..3 {
        let r = s.get(&format!("{q}&pass={pass}"));
        let img = r.png();
        assert_eq!(img.dimensions(), (48, 32));
        spp.push(r.header("x-glint-spp").unwrap().parse::<u32>().unwrap());
        assert_eq!(r.header("x-glint-target"), Some("4"));
        assert_eq!(
            r.header("x-glint-done"),
            Some(if pass == 2 { "true" } else { "false" })
        );
    }
    assert_eq!(spp, [1, 2, 4]);
    let p = s.json("/api/progress?session=t1");
    assert_eq!(
        (p["spp"].as_u64(), p["passes"].as_u64()),
        (Some(4), Some(3))
    );
    assert_eq!(p["pass_done"], p["pass_total"]);
    // Asking again past the target renders nothing more.
    let r = s.get(&format!("{q}&pass=3"));
    assert_eq!(r.header("x-glint-spp"), Some("4"));

    let cost = s.get("/api/cost?session=t1");
    let img = cost.png();
    assert_eq!(img.width(), 2 * 48 + 4);
    assert!(
        cost.header("x-glint-tests")
            .unwrap()
            .parse::<u64>()
            .unwrap()
            > 0
    );
    assert_eq!(s.get("/api/cost?session=nobody").status, 404);

    let t = s.json(&format!("/api/raytree?{SMALL}&x=24&y=16&shadows=1"));
    assert_eq!(t["pixel"], serde_json::json!([24, 16]));
    assert_eq!(t["rays"][0]["kind"], "eye");
    let t = s.json(&format!("/api/raytree?{SMALL}&x=24&y=16&overlay=1"));
    assert_eq!(
        t["overlay"].as_array().unwrap().len(),
        t["tree"]["rays"].as_array().unwrap().len()
    );

    for accel in ["grid", "bvh", "octree"] {
        let w = s.json(&format!("/api/traversal?{SMALL}&x=24&y=16&accel={accel}"));
        assert!(w["visits"].as_u64().unwrap() > 0, "{accel}: {w}");
        assert_eq!(
            w["segments"].as_array().unwrap().len(),
            w["overlay"].as_array().unwrap().len()
        );
    }
    let g = s.json(&format!("/api/grid?{SMALL}&accel=grid:4"));
    assert_eq!(g["res"], serde_json::json!([4, 4, 4]));
    assert!(g["occupied"].as_u64().unwrap() > 0);
}

/// Mean absolute difference of two images of the same size, 0-255 scale.
fn mean_abs(a: &image::RgbImage, b: &image::RgbImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let sum: u64 = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(x, y)| u64::from(x.abs_diff(*y)))
        .sum();
    sum as f64 / a.as_raw().len() as f64
}

/// The session's image after every pass up to the target.
fn refined(s: &Server, q: &str) -> image::RgbImage {
    let mut pass = 0;
    loop {
        let r = s.get(&format!("/api/render?{q}&pass={pass}"));
        let img = r.png();
        if r.header("x-glint-done") == Some("true") {
            return img;
        }
        pass = r.header("x-glint-pass").unwrap().parse().unwrap();
    }
}

/// The page's path tracer is `glint render --integrator path`'s: on the
/// Cornell box (lit only by its emitting triangles) its refined image is as
/// close to the command line's at the same samples per pixel as two
/// independent renders are, and far from the Whitted image of the same view.
/// Without `bounces`, the path tracer's own default (64) applies, as on the
/// command line.
#[test]
fn path_integrator_renders_as_glint_render() {
    let scene = common::own_scene("cornell_box.txt");
    let dir = scratch("path");
    let cli = |spp: &str, seed: &str, name: &str| {
        let out = dir.join(name);
        let o = Command::new(env!("CARGO_BIN_EXE_glint"))
            .args(["render", scene.to_str().unwrap(), "-o"])
            .arg(&out)
            .args(["--size", "48", "48", "--integrator", "path", "--spp", spp])
            .args(["--seed", seed, "-q"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        image::open(&out).unwrap().to_rgb8()
    };
    let reference = cli("64", "1", "ref.png");
    let other = cli("64", "2", "other.png");
    let s = Server::glint(&scene, &[]);
    let path = refined(&s, "w=48&h=48&spp=64&integrator=path&session=p");
    let whitted = refined(&s, "w=48&h=48&spp=64&shadows=1&session=w");
    let (d_path, d_noise, d_whitted) = (
        mean_abs(&path, &reference),
        mean_abs(&other, &reference),
        mean_abs(&whitted, &reference),
    );
    eprintln!("path tracer vs glint render: page {d_path:.2}, another seed {d_noise:.2}, Whitted {d_whitted:.2}");
    // The passes are stratified each on their own (docs/serve.md): a little
    // noisier than one 64-spp render, never more than twice.
    assert!(d_path < 2.0 * d_noise + 0.5, "{d_path} vs {d_noise}");
    assert!(d_whitted > 4.0 * d_path, "{d_whitted} vs {d_path}");
    // Bounces: 1 is direct light only, darker than the default's 64.
    let direct = refined(&s, "w=48&h=48&spp=64&integrator=path&bounces=1&session=d");
    let sum = |i: &image::RgbImage| i.as_raw().iter().map(|&v| u64::from(v)).sum::<u64>();
    assert!(
        sum(&direct) * 10 < sum(&path) * 9,
        "{} vs {}",
        sum(&direct),
        sum(&path)
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// The page's accelerators are the command line's, with its default: the
/// menu holds every accelerator once, under a name `--accel` takes, with
/// `bvh8` first and no alias (`bvh4`); `glint serve` and `glint render`
/// show the same `--accel` default.
#[test]
fn accelerators_and_default_agree_with_glint_render() {
    let s = Server::glint(&common::own_scene("whitted.txt"), &[]);
    let d = s.json("/api/status")["defaults"].clone();
    assert_eq!(d["accel"], "bvh8");
    let menu: Vec<&str> = d["accels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(menu[0], "bvh8", "{menu:?}");
    assert!(!menu.contains(&"bvh4"), "{menu:?}");
    let kinds: Vec<glint::accel::AccelKind> = menu.iter().map(|n| n.parse().unwrap()).collect();
    for (i, k) in kinds.iter().enumerate() {
        assert!(!kinds[..i].contains(k), "{} twice in {menu:?}", menu[i]);
    }
    for name in glint::accel::AccelKind::NAMES {
        let k: glint::accel::AccelKind = name.parse().unwrap();
        assert!(kinds.contains(&k), "{name} missing from {menu:?}");
    }
    assert_eq!(
        d["integrators"],
        serde_json::json!(["whitted", "ao", "path"])
    );
    let default_of = |cmd: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_glint"))
            .args([cmd, "--help"])
            .output()
            .unwrap();
        let help = String::from_utf8_lossy(&o.stdout).into_owned();
        let at = help
            .find("--accel")
            .unwrap_or_else(|| panic!("{cmd}: {help}"));
        let rest = &help[at..];
        let d = rest.find("[default: ").unwrap();
        rest[d..d + rest[d..].find(']').unwrap() + 1].to_owned()
    };
    assert_eq!(default_of("serve"), default_of("render"));
    assert_eq!(default_of("serve"), "[default: bvh8]");
}

/// Without `--port`, a taken 8837 is no error: the server listens on
/// another free port and prints it. With `--port 8837` it is (exit 2).
#[test]
fn a_taken_default_port_falls_back() {
    // Taken by this test, or already by someone else: taken either way.
    let _held = std::net::TcpListener::bind("127.0.0.1:8837");
    let scene = common::own_scene("whitted.txt");
    let s = Server::start(
        env!("CARGO_BIN_EXE_glint"),
        &["serve", scene.to_str().unwrap()],
    );
    assert_ne!(s.addr, "127.0.0.1:8837");
    assert_eq!(s.json("/api/status")["loaded"], true);
    let o = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["serve", scene.to_str().unwrap(), "--port", "8837"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("8837"));
}

/// Bad parameters get a 400 naming what is wrong; nothing renders.
#[test]
fn bad_parameters_are_refused_with_a_message() {
    let s = Server::glint(&common::own_scene("whitted.txt"), &[]);
    let cases = [
        ("/api/render?session=a&w=0", "w"),
        ("/api/render?session=a&w=99999", "w"),
        ("/api/render?session=a&h=-3", "h"),
        ("/api/render?session=a&bounces=65", "bounces"),
        ("/api/render?session=a&spp=0", "spp"),
        ("/api/render?session=a&spp=5000", "spp"),
        ("/api/render?session=a&weight=nan", "weight"),
        ("/api/render?session=a&accel=warp", "accel"),
        ("/api/render?session=a&accel=grid:1000", "accel"),
        ("/api/render?session=a&sampler=lucky", "sampler"),
        ("/api/render?session=a&filter=blur", "filter"),
        ("/api/render?session=a&integrator=path9", "integrator"),
        ("/api/render?session=a&shadows=maybe", "shadows"),
        ("/api/render?session=a&eye=1,2", "eye"),
        ("/api/render?session=a&eye=1,2,inf", "eye"),
        ("/api/render?session=a&dir=0,0,0", "dir"),
        ("/api/render?session=a&up=0,0,-1&dir=0,0,-1", "up"),
        ("/api/render?session=a&fov=180", "fov"),
        ("/api/render?session=a&pass=99999", "pass"),
        ("/api/render?session=a/b", "session"),
        ("/api/render?w=10", "session"),
        ("/api/render?session=a&frobnicate=1", "frobnicate"),
        ("/api/render?session=a&w=1&w=2", "twice"),
        ("/api/raytree?x=5", "pixel"),
        ("/api/raytree?w=10&h=10&x=10&y=0", "x"),
        ("/api/traversal?w=10&h=10&x=1&y=1&accel=none", "brute force"),
    ];
    for (path, word) in cases {
        let r = s.get(path);
        assert_eq!(r.status, 400, "{path}: {}", r.text());
        assert!(
            r.text().contains(word),
            "{path}: {:?} does not say {word}",
            r.text()
        );
        assert!(r.text().len() < 600, "{path}: a long message");
    }
    // Bodies are refused (no endpoint reads one), and only GET is served.
    let big = "x".repeat(10_000);
    let r = request(
        &s.addr,
        &format!("GET /api/status HTTP/1.1\r\nHost: x\r\nConnection: close\r\nContent-Length: {}\r\n\r\n{big}", big.len()),
    );
    assert_eq!(r.status, 413, "{}", r.text());
    let r = request(
        &s.addr,
        "POST /api/render HTTP/1.1\r\nHost: x\r\nConnection: close\r\nContent-Length: 0\r\n\r\n",
    );
    assert_eq!(r.status, 405);
}

fn write_scene(dir: &Path, name: &str, mesh: &str, background: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(
        &p,
        format!(
            "PerspectiveCamera {{ center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }}\n\
             Background {{ color {background} }}\n\
             Materials {{ numMaterials 1 PhongMaterial {{ diffuseColor 1 0 0 }} }}\n\
             Group {{ numObjects 1\n MaterialIndex 0\n TriangleMesh {{ obj_file {mesh} }}\n}}\n"
        ),
    )
    .unwrap();
    p
}

const TRIANGLE_OBJ: &str = "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n";

/// Meshes outside `--root` (by name or through a link), and anything but a
/// regular file, are refused before they are opened; a mesh's own lines
/// never reach the page.
#[test]
fn files_outside_the_root_are_refused() {
    let d = scratch("root");
    let root = d.join("root");
    std::fs::create_dir_all(&root).unwrap();
    std::fs::write(d.join("outside.obj"), TRIANGLE_OBJ).unwrap();
    std::fs::write(root.join("inside.obj"), TRIANGLE_OBJ).unwrap();

    let ok = write_scene(&root, "ok.txt", "inside.obj", "0 0 0");
    let s = Server::glint(&ok, &[]);
    assert_eq!(s.json("/api/status")["loaded"], true);
    drop(s);

    let cases: Vec<(&str, &str)> = vec![
        ("dotdot.txt", "../outside.obj"),
        ("absolute.txt", "ABS"),
        ("link.txt", "link.obj"),
        ("fifo.txt", "pipe.obj"),
    ];
    std::os::unix::fs::symlink(d.join("outside.obj"), root.join("link.obj")).unwrap();
    let fifo = Command::new("mkfifo").arg(root.join("pipe.obj")).status();
    for (name, mesh) in cases {
        if mesh == "pipe.obj" && !fifo.as_ref().is_ok_and(|s| s.success()) {
            continue;
        }
        let abs = d.join("outside.obj");
        let mesh = if mesh == "ABS" {
            abs.to_str().unwrap()
        } else {
            mesh
        };
        let scene = write_scene(&root, name, mesh, "0 0 0");
        let t = Instant::now();
        let s = Server::glint(&scene, &[]);
        let st = s.json("/api/status");
        assert_eq!(st["loaded"], false, "{name}: {st}");
        let text = st["error"]["text"].as_str().unwrap();
        let why = if name == "fifo.txt" {
            "not a regular file"
        } else {
            "outside the served root"
        };
        assert!(text.contains(why), "{name}: {text}");
        assert_eq!(st["error"]["line"], 6, "{name}: {st}");
        let r = s.get("/api/render?session=a&w=8&h=8");
        assert_eq!(r.status, 409, "{name}: {}", r.text());
        no_hang(t, &format!("{name}: blocked"));
    }

    // The whole scene file outside the root is refused at start.
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["serve", ok.to_str().unwrap(), "--port", "0", "--root"])
        .arg(d.join("elsewhere-that-does-not-exist"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let sub = d.join("sub");
    std::fs::create_dir_all(&sub).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["serve", ok.to_str().unwrap(), "--port", "0", "--root"])
        .arg(&sub)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("outside the served root"));

    // A bad mesh inside the root: its line and the token found there stay
    // on the server.
    std::fs::write(
        root.join("secret.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 TOPSECRET\n",
    )
    .unwrap();
    let scene = write_scene(&root, "secret.txt", "secret.obj", "0 0 0");
    let s = Server::glint(&scene, &[]);
    let st = s.json("/api/status");
    assert_eq!(st["loaded"], false, "{st}");
    let all = st.to_string();
    assert!(
        !all.contains("TOPSECRET"),
        "mesh contents reached the page: {all}"
    );
    assert!(all.contains("secret.obj"), "{all}");
}

/// Saving the scene re-renders it; a broken save shows file, line, column
/// and the caret, and the last good scene keeps rendering.
#[test]
fn edits_reload_and_errors_keep_the_last_good_scene() {
    let d = scratch("watch");
    std::fs::write(d.join("tri.obj"), TRIANGLE_OBJ).unwrap();
    let scene = write_scene(&d, "scene.txt", "tri.obj", "0 0 0");
    let s = Server::glint(&scene, &[]);
    let q = "/api/render?session=w&w=16&h=16&spp=1&pass=0";
    let corner = |r: &Reply| *r.png().get_pixel(0, 0);
    assert_eq!(corner(&s.get(q)).0, [0, 0, 0]);
    let v1 = s.json("/api/status")["version"].as_u64().unwrap();

    write_scene(&d, "scene.txt", "tri.obj", "0 0 1");
    s.wait_status(|st| st["version"].as_u64() > Some(v1));
    assert_eq!(corner(&s.get(q)).0, [0, 0, 255]);

    // Line 2, column 20: the third number of the colour is missing.
    std::fs::write(
        &scene,
        "PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }\nBackground { color 0 1 }\n",
    )
    .unwrap();
    let st = s.wait_status(|st| !st["error"].is_null());
    let e = &st["error"];
    assert_eq!(e["file"], "scene.txt");
    assert_eq!(e["line"], 2);
    assert!(e["column"].as_u64().unwrap() > 1);
    let text = e["text"].as_str().unwrap();
    assert!(text.contains("scene.txt:2:"), "{text}");
    assert!(text.contains("Background { color 0 1 }"), "{text}");
    assert!(text.contains('^'), "{text}");
    assert_eq!(st["loaded"], true);
    // The last good scene still renders (blue background).
    assert_eq!(corner(&s.get(q)).0, [0, 0, 255]);
}

/// The ray tree of the course's faceted gem, pixel (100, 100), over HTTP
/// is `glint raytree`'s JSON for the same settings.
#[test]
fn raytree_over_http_equals_the_cli() {
    let Some(dir) = common::scenes("raytree_over_http_equals_the_cli") else {
        return;
    };
    let scene = dir.join("scene4_14_faceted_gem.txt");
    let out_dir = scratch("raytree");
    let json = out_dir.join("tree.json");
    let cli = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args([
            "raytree",
            scene.to_str().unwrap(),
            "--pixel",
            "100",
            "100",
            "-o",
        ])
        .arg(&json)
        .args([
            "--size",
            "200",
            "200",
            "--shadows",
            "--shade-back",
            "--bounces",
            "3",
            "--weight",
            "0.01",
        ])
        .output()
        .unwrap();
    assert!(
        cli.status.success(),
        "{}",
        String::from_utf8_lossy(&cli.stderr)
    );
    let want: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let s = Server::glint(&scene, &[]);
    let got =
        s.json("/api/raytree?w=200&h=200&x=100&y=100&shadows=1&shade_back=1&bounces=3&weight=0.01");
    assert!(want["rays"].as_array().unwrap().len() > 3, "{want}");
    assert_eq!(got, want);
}

/// Twenty clients at once all get their images, and the server's threads
/// stay bounded while they wait.
#[test]
fn twenty_clients_get_their_images() {
    let s = Server::glint(&common::own_scene("whitted.txt"), &[]);
    let pid = s.child.id();
    let threads = move || -> usize {
        std::fs::read_to_string(format!("/proc/{pid}/status"))
            .ok()
            .and_then(|st| {
                st.lines()
                    .find(|l| l.starts_with("Threads:"))
                    .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
            })
            .unwrap_or(0)
    };
    let most = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let watcher = {
        let (most, done) = (most.clone(), done.clone());
        std::thread::spawn(move || {
            while !done.load(std::sync::atomic::Ordering::SeqCst) {
                most.fetch_max(threads(), std::sync::atomic::Ordering::SeqCst);
                std::thread::sleep(Duration::from_millis(5));
            }
        })
    };
    let addr = s.addr.clone();
    let clients: Vec<_> = (0..20)
        .map(|i| {
            let addr = addr.clone();
            std::thread::spawn(move || {
                let path = format!("/api/render?session=c{i}&w=96&h=64&spp=2&pass=0");
                request(
                    &addr,
                    &format!("GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"),
                )
            })
        })
        .collect();
    for c in clients {
        let r = c.join().unwrap();
        assert_eq!(r.png().dimensions(), (96, 64));
    }
    done.store(true, std::sync::atomic::Ordering::SeqCst);
    watcher.join().unwrap();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let most = most.load(std::sync::atomic::Ordering::SeqCst);
    // Main, 2 runtime workers, the render pool, at most 6 blocking threads.
    assert!(most <= cores + 12, "{most} threads for 20 clients");
}

/// Sends `GET path` from another thread, and returns once session
/// `session` exists on the server (its render begun) and, with
/// `pass_started`, its pass has counted its pixels.
fn render_in_background(
    s: &Server,
    path: &str,
    session: &str,
    pass_started: bool,
) -> std::thread::JoinHandle<Reply> {
    let (addr, path) = (s.addr.clone(), path.to_string());
    let handle = std::thread::spawn(move || {
        request(
            &addr,
            &format!("GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"),
        )
    });
    let progress = format!("/api/progress?session={session}");
    let t = Instant::now();
    while s.get(&progress).status != 200 || (pass_started && s.json(&progress)["pass_total"] == 0) {
        no_hang(t, "the background render never started");
        std::thread::sleep(Duration::from_millis(5));
    }
    handle
}

/// A new request of a session cancels the render it had running.
#[test]
fn a_new_request_cancels_the_session_render() {
    let s = Server::glint(&common::own_scene("mesh_knot_16k.txt"), &[]);
    let slow = render_in_background(
        &s,
        "/api/render?session=one&w=2048&h=2048&accel=none&spp=1&pass=0",
        "one",
        true,
    );
    let t = Instant::now();
    let fast = s.get("/api/render?session=one&w=8&h=8&spp=1&pass=0");
    assert_eq!(fast.png().dimensions(), (8, 8));
    let slow = slow.join().unwrap();
    assert_eq!(slow.status, 409, "{}", slow.text());
    assert!(slow.text().contains("superseded"));
    no_hang(t, "the superseded render was not stopped");
}

/// Requests travel on separate connections and may arrive out of order: one
/// numbered lower than a request the session has seen (`seq`) is answered
/// 409 at once, and neither cancels the newer render nor touches its image.
#[test]
fn a_late_older_request_cancels_nothing() {
    let s = Server::glint(&common::own_scene("mesh_knot_16k.txt"), &[]);
    let newer = render_in_background(
        &s,
        "/api/render?session=two&w=1024&h=1024&spp=4&seq=5&pass=0",
        "two",
        false,
    );
    let older = s.get("/api/render?session=two&w=8&h=8&spp=1&seq=4&pass=0");
    assert_eq!(older.status, 409, "{}", older.text());
    assert!(older.text().contains("superseded"));
    let newer = newer.join().unwrap();
    assert_eq!(newer.png().dimensions(), (1024, 1024));
    assert_eq!(newer.header("x-glint-spp"), Some("1"));
    // The newer render goes on from its own pass.
    let next = s.get("/api/render?session=two&w=1024&h=1024&spp=4&seq=5&pass=1");
    assert_eq!(next.header("x-glint-spp"), Some("2"), "{}", next.text());
    // Without a number a request always goes ahead, as before.
    let plain = s.get("/api/render?session=two&w=8&h=8&spp=1&pass=0");
    assert_eq!(plain.png().dimensions(), (8, 8));
    assert_eq!(
        s.get("/api/render?session=two&w=8&h=8&spp=1&seq=x&pass=0")
            .status,
        400
    );
}

/// Ctrl-C (SIGINT) stops the server cleanly, with status 0.
#[test]
fn ctrl_c_stops_the_server() {
    let mut s = Server::glint(&common::own_scene("whitted.txt"), &[]);
    assert_eq!(s.json("/api/status")["loaded"], true);
    let ok = Command::new("kill")
        .args(["-INT", &s.child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
    let t = Instant::now();
    let status = loop {
        if let Some(st) = s.child.try_wait().unwrap() {
            break st;
        }
        no_hang(t, "still running");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert!(status.success(), "{status:?}");
    let mut err = String::new();
    s.child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    assert!(err.contains("stopping"), "{err}");
}

/// `raytracer ... -gui` starts the server on the scene and prints its address.
#[test]
fn raytracer_gui_starts_the_server() {
    let scene = common::own_scene("whitted.txt");
    let s = Server::start(
        env!("CARGO_BIN_EXE_raytracer"),
        &[
            "-input",
            scene.to_str().unwrap(),
            "-size",
            "120",
            "80",
            "-bounces",
            "2",
            "-shadows",
            "-gui",
        ],
    );
    let st = s.json("/api/status");
    assert_eq!(st["loaded"], true);
    assert_eq!(
        (st["defaults"]["w"].as_u64(), st["defaults"]["h"].as_u64()),
        (Some(120), Some(80))
    );
    assert_eq!(st["defaults"]["shadows"], true);
    assert_eq!(
        s.get("/api/render?session=g&pass=0&spp=1")
            .png()
            .dimensions(),
        (120, 80)
    );
}

/// The handouts' lines (`-output` and `-gui`) run from a script still
/// render their image and end: the browser view starts only at a terminal.
#[test]
fn raytracer_gui_with_output_in_a_script_renders_and_ends() {
    let d = scratch("gui-output");
    let scene = common::own_scene("whitted.txt");
    let out = Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args([
            "-input",
            scene.to_str().unwrap(),
            "-size",
            "40",
            "30",
            "-output",
        ])
        .arg(d.join("out.png"))
        .args(["-gui", "-tessellation", "10", "5"])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(d.join("out.png").exists());
    assert!(String::from_utf8_lossy(&out.stderr).contains("-gui: rendering"));
}

/// The page in a real browser: `tests/browser/test_serve_page.py`, run by
/// pytest with Playwright driving Debian's chromium. Skipped (with a note)
/// where chromium, Playwright, pytest or Pillow are missing, unless
/// `GLINT_REQUIRE_BROWSER=1` (as `.ci/run` sets), which makes that a failure.
/// Screenshots go to `target/serve-screenshots/`.
#[test]
fn browser_page() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let required = std::env::var("GLINT_REQUIRE_BROWSER").is_ok_and(|v| v == "1");
    let chromium = std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    let python = Command::new("python3")
        .args(["-c", "import playwright, pytest, PIL"])
        .output();
    let missing = if !Path::new(&chromium).exists() {
        Some(format!(
            "no chromium at {chromium} (apt-get install chromium)"
        ))
    } else if !python.as_ref().is_ok_and(|o| o.status.success()) {
        Some("python3 cannot import playwright, pytest and PIL (pip install playwright pytest Pillow)".into())
    } else {
        None
    };
    if let Some(why) = missing {
        assert!(!required, "GLINT_REQUIRE_BROWSER=1 but {why}");
        let _ = writeln!(std::io::stderr(), "skipped browser_page: {why}");
        return;
    }
    let shots = repo.join("target").join("serve-screenshots");
    let out = Command::new("python3")
        .args([
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "tests/browser",
        ])
        .current_dir(repo)
        .env("GLINT_BIN", env!("CARGO_BIN_EXE_glint"))
        .env("GLINT_SHOTS", &shots)
        .env("CHROMIUM", &chromium)
        .output()
        .expect("run pytest");
    assert!(
        out.status.success(),
        "browser tests failed (screenshots in {}):\n{}\n{}",
        shots.display(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
