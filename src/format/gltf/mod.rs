//! glTF 2.0 scenes (`.gltf` with its buffers, and `.glb`).
//!
//! The `gltf` crate parses and validates the document (JSON or GLB); glint
//! resolves the buffers and reads the accessors itself, so that every byte
//! read is checked against the limits of `docs/reliability.md`:
//!
//! - a buffer's `uri` is a `data:` URI (base64) or a relative path inside
//!   the file's folder (no absolute paths, no `..`, no scheme, no symbolic
//!   link leading out); external files are read with the same bound as any
//!   input;
//! - every accessor is checked against its buffer view and buffer (offset,
//!   stride, count, with overflow-checked arithmetic) before it is read, and
//!   every index against the vertex count; sparse accessors are refused;
//! - the node hierarchy is walked at most [`MAX_DEPTH`] deep and at most
//!   [`MAX_NODE_VISITS`] node visits (a node used by many parents is
//!   instanced, and a malicious DAG could otherwise ask for 2⁶⁴ copies).
//!
//! What becomes what:
//!
//! - Nodes become [`Node::Transform`]s around their meshes: glint's
//!   flattening bakes them (`world::build`). Each triangle primitive
//!   (`TRIANGLES`, `TRIANGLE_STRIP`, `TRIANGLE_FAN`; indexed or not) is a
//!   [`Mesh`], shared by every node that uses it; `NORMAL`s make it smooth.
//!   Points and lines are skipped.
//! - The first camera met (scene order, depth first) is the camera; without
//!   one the scene is framed like a bare mesh ([`Scene::for_mesh`]'s view).
//!   A perspective camera's `yfov` is vertical; glint's angle spans the
//!   longer image side, so with an `aspectRatio` above 1 it becomes
//!   `2·atan(tan(yfov/2)·aspectRatio)`. Orthographic: the larger of
//!   `2·xmag` and `2·ymag`.
//! - Materials (metallic-roughness) become Phong parameters (textures are
//!   not read; the physical reading belongs to the path tracer's BSDFs):
//!   with base colour `c`, metallic `m`, roughness `r`:
//!   `diffuse = c·(1 − m) + c·m·r` (a rough metal scatters like a diffuse
//!   surface of its colour), `specular = (0.04·(1 − m) + c·m)·(1 − r)`,
//!   `exponent = 2/r⁴ − 2` (the Blinn-Phong lobe of the same width as a
//!   GGX lobe of roughness `α = r²`), clamped to `[1, 10⁴]`,
//!   `reflective = c·m·(1 − r)²` and `glossiness = r` (blurred mirrors);
//!   `alphaMode: BLEND` makes the surface `1 − alpha` transparent (no
//!   refraction). `emissiveFactor` becomes the emitted radiance
//!   (`emittedColor`, seen by the path tracer). No material: glTF's default
//!   (white, `m = 1`, `r = 1`), a white diffuse surface by the rule above.
//! - `KHR_lights_punctual`: directional lights along the node's −z,
//!   point and spot lights (spots without their cone) at the node's origin
//!   with inverse-square fall-off; a glTF intensity `I` of colour `k`
//!   becomes the glint colour `k·I/π` (glint's Phong has no `1/π`). With no
//!   lights, the bare-mesh default light and ambient light.

#[cfg(test)]
mod tests;
mod uri;

use super::diagnostic::{quote, ParseError};
use crate::math::{Aabb, Vec3};
use crate::scene::{
    Background, Camera, Light, Material, Mesh, Node, Phong, Scene, ShapeDesc as Shape,
};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use uri::{read_uri, resolve_uri};

/// Deepest node nesting followed.
pub const MAX_DEPTH: usize = 256;

/// Most node visits (instances) in one scene.
pub const MAX_NODE_VISITS: usize = 1 << 20;

/// Reads a glTF or GLB file into a scene.
pub fn load_gltf(path: &Path) -> Result<Scene, ParseError> {
    load_gltf_files(path).map(|(s, _)| s)
}

/// [`load_gltf`], and every file read (the document first, then its
/// external buffers).
pub fn load_gltf_files(path: &Path) -> Result<(Scene, Vec<PathBuf>), ParseError> {
    let bytes = super::input::read_input(path)
        .map_err(|e| ParseError::unreadable(path, &e, "a readable glTF file"))?;
    let folder = path.parent().unwrap_or(Path::new("")).to_owned();
    let mut files = vec![path.to_owned()];
    let scene = parse_gltf(&bytes, path, &mut |uri| {
        let p = resolve_uri(&folder, uri)?;
        let data = super::input::read_input(&p)
            .map_err(|e| format!("{} ({})", p.display(), super::diagnostic::io_reason(&e)))?;
        files.push(p);
        Ok(data)
    })?;
    Ok((scene, files))
}

/// Parses a glTF document (JSON or GLB) already in memory; `path` names it
/// in messages, and `external` reads a buffer's relative URI (the
/// percent-decoded path) or says why not.
pub fn parse_gltf(
    bytes: &[u8],
    path: &Path,
    external: &mut dyn FnMut(&str) -> Result<Vec<u8>, String>,
) -> Result<Scene, ParseError> {
    let err = |expected: &str, found: String| ParseError::at(path, "", 0, 0, expected, found);
    let parsed = gltf::Gltf::from_slice_without_validation(bytes).and_then(|g| {
        // gltf-json 1.4's validation indexes the accessor of a POSITION
        // attribute before checking that it exists (a panic on a
        // dangling index): check those first, then validate.
        let json = g.document.as_json();
        for (m, mesh) in json.meshes.iter().enumerate() {
            for (p, prim) in mesh.primitives.iter().enumerate() {
                for (semantic, acc) in &prim.attributes {
                    if acc.value() >= json.accessors.len() {
                        let path = gltf::json::Path::new()
                            .field("meshes")
                            .index(m)
                            .field("primitives")
                            .index(p)
                            .field("attributes")
                            .key(&format!("{semantic:?}"));
                        let e = gltf::json::validation::Error::IndexOutOfBounds;
                        return Err(gltf::Error::Validation(vec![(path, e)]));
                    }
                }
            }
        }
        let blob = g.blob;
        let document = gltf::Document::from_json(g.document.into_json())?;
        Ok(gltf::Gltf { document, blob })
    });
    let gltf = parsed.map_err(|e| match e {
        gltf::Error::Deserialize(j) if j.line() > 0 => {
            let text = String::from_utf8_lossy(bytes);
            ParseError::at(
                path,
                &text,
                j.line(),
                j.column(),
                "valid glTF JSON",
                j.to_string(),
            )
        }
        gltf::Error::Validation(v) => {
            let list: Vec<String> = v
                .iter()
                .take(3)
                .map(|(p, e)| format!("{e} at {p}"))
                .collect();
            err("a valid glTF 2.0 document", list.join("; "))
        }
        other => err("a glTF 2.0 document (JSON or GLB)", other.to_string()),
    })?;
    if let Some(ext) = gltf
        .extensions_required()
        .find(|e| *e != "KHR_lights_punctual")
    {
        return Err(err(
            "no required extension glint lacks",
            format!("extensionsRequired {}", quote(ext)),
        ));
    }
    // Buffers.
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    let mut blob = gltf.blob.clone();
    for b in gltf.buffers() {
        let at = format!("buffer {}", b.index());
        let data = match b.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                err(
                    "a GLB binary chunk for the buffer without a uri",
                    format!("none ({at})"),
                )
            })?,
            gltf::buffer::Source::Uri(uri) => read_uri(uri, external)
                .map_err(|why| err(&format!("a readable uri for {at}"), why))?,
        };
        if data.len() < b.length() {
            return Err(err(
                &format!("{} bytes in {at} (its byteLength)", b.length()),
                format!("{} bytes", data.len()),
            ));
        }
        buffers.push(data);
    }
    let mut loader = Loader {
        buffers: &buffers,
        path,
        meshes: HashMap::new(),
        materials: Vec::new(),
        material_of: HashMap::new(),
        lights: Vec::new(),
        camera: None,
        visits: 0,
        bounds: Aabb::EMPTY,
    };
    let roots: Vec<gltf::Node> = match gltf.default_scene().or_else(|| gltf.scenes().next()) {
        Some(s) => s.nodes().collect(),
        None => {
            // No scene: every node that is nobody's child.
            let mut child = vec![false; gltf.nodes().len()];
            for n in gltf.nodes() {
                for c in n.children() {
                    child[c.index()] = true;
                }
            }
            gltf.nodes().filter(|n| !child[n.index()]).collect()
        }
    };
    let mut top = Vec::new();
    for n in roots {
        if let Some(node) = loader.node(&n, glam::DMat4::IDENTITY, 0)? {
            top.push(node);
        }
    }
    if loader.bounds.is_empty() {
        return Err(err(
            "a glTF scene with at least one triangle",
            "no triangle primitives".into(),
        ));
    }
    let framed = Scene::for_bounds(loader.bounds);
    let lights_given = !loader.lights.is_empty();
    Ok(Scene {
        camera: loader.camera.unwrap_or(framed.camera),
        lights: if lights_given {
            loader.lights
        } else {
            framed.lights
        },
        background: if lights_given {
            Background {
                color: Vec3::splat(0.2),
                ambient: Vec3::ZERO,
            }
        } else {
            framed.background
        },
        materials: loader.materials,
        root: Node::Group(top),
        effects: Default::default(),
    })
}

struct Loader<'a> {
    buffers: &'a [Vec<u8>],
    path: &'a Path,
    /// Meshes by (mesh, primitive) index.
    meshes: HashMap<(usize, usize), Option<Arc<Mesh>>>,
    materials: Vec<Material>,
    /// glint material index by glTF material index (`None`: the default).
    material_of: HashMap<Option<usize>, usize>,
    lights: Vec<Light>,
    camera: Option<Camera>,
    visits: usize,
    /// World bounds of all triangles (for framing).
    bounds: Aabb,
}

impl Loader<'_> {
    fn err(&self, expected: &str, found: String) -> ParseError {
        ParseError::at(self.path, "", 0, 0, expected, found)
    }

    /// The subtree of `node`, whose parent maps into world space by `m`.
    fn node(
        &mut self,
        node: &gltf::Node,
        parent: glam::DMat4,
        depth: usize,
    ) -> Result<Option<Node>, ParseError> {
        self.visits += 1;
        if depth >= MAX_DEPTH || self.visits > MAX_NODE_VISITS {
            return Err(self.err(
                &format!(
                    "a node hierarchy at most {MAX_DEPTH} deep with at most {MAX_NODE_VISITS} \
                     node instances"
                ),
                format!(
                    "more at node {} (a cycle, or too much instancing)",
                    node.index()
                ),
            ));
        }
        let local = node_matrix(node);
        let m = parent * local;
        if let Some(cam) = node.camera() {
            if self.camera.is_none() {
                self.camera = camera(&cam, m);
            }
        }
        if let Some(light) = node.light() {
            self.lights.extend(punctual(&light, m));
        }
        let mut children = Vec::new();
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                let key = (mesh.index(), prim.index());
                let built = match self.meshes.get(&key) {
                    Some(m) => m.clone(),
                    None => {
                        let m = self.primitive(&mesh, &prim)?.map(Arc::new);
                        self.meshes.insert(key, m.clone());
                        m
                    }
                };
                let Some(built) = built else { continue };
                let mf = m.as_mat4();
                self.bounds = built
                    .positions
                    .iter()
                    .fold(self.bounds, |b, &p| b.grow(mf.transform_point3(p)));
                let material = self.material(prim.material());
                children.push(Node::Shape {
                    shape: Shape::Mesh(built),
                    material: Some(material),
                });
            }
        }
        for c in node.children() {
            if let Some(n) = self.node(&c, m, depth + 1)? {
                children.push(n);
            }
        }
        if children.is_empty() {
            return Ok(None);
        }
        let group = Node::Group(children);
        Ok(Some(if local == glam::DMat4::IDENTITY {
            group
        } else {
            Node::Transform {
                matrix: local,
                child: Box::new(group),
            }
        }))
    }

    /// The glint material for a glTF material (added once).
    fn material(&mut self, m: gltf::Material) -> usize {
        if let Some(&i) = self.material_of.get(&m.index()) {
            return i;
        }
        let phong = phong_of(&m);
        self.materials.push(Material::Phong(phong));
        let i = self.materials.len() - 1;
        self.material_of.insert(m.index(), i);
        i
    }

    /// The mesh of one primitive, `None` for points and lines.
    fn primitive(
        &self,
        mesh: &gltf::Mesh,
        prim: &gltf::Primitive,
    ) -> Result<Option<Mesh>, ParseError> {
        use gltf::mesh::Mode;
        let at = format!("mesh {} primitive {}", mesh.index(), prim.index());
        let mode = prim.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            return Ok(None);
        }
        let pos = prim
            .get(&gltf::Semantic::Positions)
            .ok_or_else(|| self.err("a POSITION attribute", format!("none in {at}")))?;
        let positions = self.vec3s(&pos, &at, "POSITION")?;
        if let Some(k) = positions.iter().position(|p| !p.is_finite()) {
            return Err(self.err(
                "finite positions",
                format!(
                    "{} at vertex {k} of accessor {} ({at})",
                    positions[k],
                    pos.index()
                ),
            ));
        }
        let n = positions.len();
        let corners: Vec<u32> = match prim.indices() {
            Some(acc) => {
                let idx = self.indices(&acc, &at)?;
                if let Some(&bad) = idx.iter().find(|&&i| i as usize >= n) {
                    return Err(self.err(
                        &format!("indices below the {n} vertices of {at}"),
                        format!("{bad} in accessor {}", acc.index()),
                    ));
                }
                idx
            }
            None => (0..n as u32).collect(),
        };
        let triangles: Vec<[u32; 3]> = match mode {
            Mode::Triangles => corners
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
            Mode::TriangleStrip => (2..corners.len())
                .map(|k| {
                    let (a, b, c) = (corners[k - 2], corners[k - 1], corners[k]);
                    if k % 2 == 0 {
                        [a, b, c]
                    } else {
                        [b, a, c]
                    }
                })
                .collect(),
            _ => (2..corners.len())
                .map(|k| [corners[0], corners[k - 1], corners[k]])
                .collect(),
        };
        if triangles.is_empty() {
            return Ok(None);
        }
        let normals = match prim.get(&gltf::Semantic::Normals) {
            Some(acc) => {
                let v = self.vec3s(&acc, &at, "NORMAL")?;
                if v.len() != n {
                    return Err(self.err(
                        &format!("{n} normals, one per POSITION ({at})"),
                        format!("{} in accessor {}", v.len(), acc.index()),
                    ));
                }
                v.iter()
                    .map(|n| n.try_normalize().unwrap_or(Vec3::ZERO))
                    .collect()
            }
            None => Vec::new(),
        };
        Ok(Some(Mesh {
            positions,
            triangles,
            normals,
            colors: Vec::new(),
        }))
    }

    /// The bytes of element `k` of an accessor, checked: `(data, stride,
    /// element size)`.
    fn elements(
        &self,
        acc: &gltf::Accessor,
        at: &str,
        size: usize,
    ) -> Result<(&[u8], usize), ParseError> {
        let what = format!("accessor {} ({at})", acc.index());
        if acc.sparse().is_some() {
            return Err(self.err(
                "an accessor without sparse storage",
                format!("a sparse {what}"),
            ));
        }
        let Some(view) = acc.view() else {
            return Err(self.err("an accessor with a bufferView", format!("none in {what}")));
        };
        let buffer = &self.buffers[view.buffer().index()];
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return Err(self.err(
                &format!("a byteStride of at least {size}"),
                format!("{stride} in {what}"),
            ));
        }
        let view_end = view.offset().checked_add(view.length());
        let view_bytes = view_end
            .and_then(|e| buffer.get(view.offset()..e))
            .ok_or_else(|| {
                self.err(
                    &format!("buffer view {} inside its buffer", view.index()),
                    format!(
                        "bytes {}+{} of a buffer of {} ({what})",
                        view.offset(),
                        view.length(),
                        buffer.len()
                    ),
                )
            })?;
        let count = acc.count();
        if count == 0 {
            return Ok((&[], stride));
        }
        let end = (count - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(size))
            .and_then(|x| x.checked_add(acc.offset()));
        let data = end
            .and_then(|e| view_bytes.get(acc.offset()..e))
            .ok_or_else(|| {
                self.err(
                    &format!("{count} elements inside buffer view {}", view.index()),
                    format!("a view of {} bytes ({what})", view_bytes.len()),
                )
            })?;
        Ok((data, stride))
    }

    /// A `VEC3` of `FLOAT` accessor.
    fn vec3s(&self, acc: &gltf::Accessor, at: &str, name: &str) -> Result<Vec<Vec3>, ParseError> {
        use gltf::accessor::{DataType, Dimensions};
        if acc.data_type() != DataType::F32 || acc.dimensions() != Dimensions::Vec3 {
            return Err(self.err(
                &format!("{name} as VEC3 of FLOAT"),
                format!(
                    "{:?} of {:?} in accessor {} ({at})",
                    acc.dimensions(),
                    acc.data_type(),
                    acc.index()
                ),
            ));
        }
        let (data, stride) = self.elements(acc, at, 12)?;
        let f = |b: &[u8], k: usize| f32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
        Ok((0..acc.count())
            .map(|i| {
                let b = &data[i * stride..];
                Vec3::new(f(b, 0), f(b, 4), f(b, 8))
            })
            .collect())
    }

    /// A `SCALAR` index accessor of unsigned bytes, shorts or ints.
    fn indices(&self, acc: &gltf::Accessor, at: &str) -> Result<Vec<u32>, ParseError> {
        use gltf::accessor::{DataType, Dimensions};
        let size = match acc.data_type() {
            DataType::U8 => 1,
            DataType::U16 => 2,
            DataType::U32 => 4,
            other => {
                return Err(self.err(
                    "indices of UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT",
                    format!("{other:?} in accessor {} ({at})", acc.index()),
                ))
            }
        };
        if acc.dimensions() != Dimensions::Scalar {
            return Err(self.err(
                "SCALAR indices",
                format!("{:?} in accessor {} ({at})", acc.dimensions(), acc.index()),
            ));
        }
        let (data, stride) = self.elements(acc, at, size)?;
        Ok((0..acc.count())
            .map(|i| {
                let b = &data[i * stride..];
                match size {
                    1 => b[0] as u32,
                    2 => u16::from_le_bytes([b[0], b[1]]) as u32,
                    _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                }
            })
            .collect())
    }
}

/// A node's local matrix, in f64 (composed from T·R·S when given so).
fn node_matrix(node: &gltf::Node) -> glam::DMat4 {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            glam::DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from)))
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let [x, y, z, w] = rotation.map(f64::from);
            let q = glam::DQuat::from_xyzw(x, y, z, w);
            let q = if q.length_squared() > 0.0 {
                q.normalize()
            } else {
                glam::DQuat::IDENTITY
            };
            glam::DMat4::from_scale_rotation_translation(
                glam::DVec3::from(scale.map(f64::from)),
                q,
                glam::DVec3::from(translation.map(f64::from)),
            )
        }
    }
}

/// The camera of a node whose matrix is `m`: it looks down its −z with +y up.
fn camera(cam: &gltf::Camera, m: glam::DMat4) -> Option<Camera> {
    let center = m.transform_point3(glam::DVec3::ZERO);
    let direction = m
        .transform_vector3(glam::DVec3::NEG_Z)
        .normalize_or_zero()
        .as_vec3();
    let up = m
        .transform_vector3(glam::DVec3::Y)
        .normalize_or_zero()
        .as_vec3();
    if direction == Vec3::ZERO || up == Vec3::ZERO || !center.as_vec3().is_finite() {
        return None;
    }
    Some(match cam.projection() {
        gltf::camera::Projection::Perspective(p) => {
            let y = p.yfov() as f64;
            let a = p.aspect_ratio().map_or(1.0, f64::from);
            let angle = if a > 1.0 {
                2.0 * ((y / 2.0).tan() * a).atan()
            } else {
                y
            };
            Camera::Perspective {
                center,
                direction,
                up,
                angle_deg: angle.to_degrees().clamp(1e-3, 179.0) as f32,
            }
        }
        gltf::camera::Projection::Orthographic(o) => Camera::Orthographic {
            center,
            direction,
            up,
            size: (2.0 * o.xmag().abs().max(o.ymag().abs())).max(1e-6),
        },
    })
}

/// A punctual light at a node whose matrix is `m`.
fn punctual(light: &gltf::khr_lights_punctual::Light, m: glam::DMat4) -> Option<Light> {
    use gltf::khr_lights_punctual::Kind;
    let k = light.intensity() / std::f32::consts::PI;
    let color =
        (Vec3::from(light.color()) * k).clamp(Vec3::ZERO, Vec3::splat(crate::limits::MAX_COLOR));
    if !color.is_finite() {
        return None;
    }
    Some(match light.kind() {
        Kind::Directional => Light::Directional {
            direction: m
                .transform_vector3(glam::DVec3::NEG_Z)
                .normalize_or_zero()
                .as_vec3(),
            color,
        },
        Kind::Point | Kind::Spot { .. } => Light::Point {
            position: m.transform_point3(glam::DVec3::ZERO),
            color,
            attenuation: Vec3::new(0.0, 0.0, 1.0),
        },
    })
}

/// The Phong reading of a metallic-roughness material (module docs).
fn phong_of(m: &gltf::Material) -> Phong {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, a] = pbr.base_color_factor();
    let c = Vec3::new(r, g, b).clamp(Vec3::ZERO, Vec3::ONE);
    let metal = pbr.metallic_factor().clamp(0.0, 1.0);
    let rough = pbr.roughness_factor().clamp(0.0, 1.0);
    let smooth = 1.0 - rough;
    let alpha = match m.alpha_mode() {
        gltf::material::AlphaMode::Blend => a.clamp(0.0, 1.0),
        _ => 1.0,
    };
    let r4 = (rough * rough * rough * rough).max(1e-8);
    Phong {
        diffuse: c * (1.0 - metal) + c * metal * rough,
        specular: (Vec3::splat(0.04 * (1.0 - metal)) + c * metal) * smooth,
        exponent: (2.0 / r4 - 2.0).clamp(1.0, 1e4),
        reflective: c * metal * smooth * smooth,
        transparent: Vec3::splat(1.0 - alpha),
        ior: 1.0,
        glossiness: rough,
        // glTF's `emissiveFactor` is the emitted radiance (without a texture).
        emission: Vec3::from(m.emissive_factor()),
    }
}

/// The triangles of a glTF scene as one mesh in the scene's space (every
/// node's transform applied, in f64): what `TriangleMesh { obj_file
/// x.glb }` gets. Normals are kept when every primitive has them.
pub(crate) fn flatten_to_mesh(scene: &Scene) -> Mesh {
    fn walk(n: &Node, m: glam::DMat4, out: &mut Mesh, all_normals: &mut bool) {
        match n {
            Node::Group(c) => c.iter().for_each(|c| walk(c, m, out, all_normals)),
            Node::Transform { matrix, child } => walk(child, m * *matrix, out, all_normals),
            Node::Moving { child, .. } => walk(child, m, out, all_normals),
            Node::Shape {
                shape: Shape::Mesh(mesh),
                ..
            } => {
                let base = out.positions.len() as u32;
                let flip = m.determinant() < 0.0;
                out.positions.extend(
                    (mesh.positions.iter()).map(|p| m.transform_point3(p.as_dvec3()).as_vec3()),
                );
                out.triangles.extend(mesh.triangles.iter().map(|t| {
                    let t = t.map(|i| i + base);
                    if flip {
                        [t[0], t[2], t[1]]
                    } else {
                        t
                    }
                }));
                *all_normals &= !mesh.normals.is_empty();
                let nm = glam::DMat3::from_mat4(m).inverse().transpose();
                out.normals.extend(mesh.normals.iter().map(|n| {
                    (nm * n.as_dvec3())
                        .try_normalize()
                        .map_or(Vec3::ZERO, |n| n.as_vec3())
                }));
            }
            Node::Shape { .. } => {}
        }
    }
    let mut out = Mesh::default();
    let mut all_normals = true;
    walk(
        &scene.root,
        glam::DMat4::IDENTITY,
        &mut out,
        &mut all_normals,
    );
    if !all_normals || out.normals.len() != out.positions.len() {
        out.normals.clear();
    }
    out
}
