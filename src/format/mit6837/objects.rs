//! The object tree: groups with their sticky `MaterialIndex`, transforms,
//! spheres, planes, triangles and meshes.

use super::cursor::{closing, plural, vec_text, Parser};
use super::lexer::{Kind, Token};
use super::Result;
use crate::format::diagnostic::{io_reason, quote};
use crate::format::obj::LoadError;
use crate::math::{Keyframe, Motion, Quat};
use crate::scene::{Node, ShapeDesc};
use glam::DVec3;
use std::path::Path;
use std::sync::Arc;

/// The keywords that start an object.
const OBJECTS: [&str; 7] = [
    "Sphere",
    "Plane",
    "Triangle",
    "TriangleMesh",
    "Group",
    "Transform",
    "KeyframedTransform",
];

/// Deepest Group/Transform nesting accepted: far beyond any real scene, far
/// below what would exhaust a thread's stack.
const MAX_DEPTH: usize = 256;

/// Material indices a Group's children start with: the enclosing one's.
type Current = Option<usize>;

impl<'a> Parser<'a> {
    /// `Group { numObjects n (MaterialIndex i | object)* }`. The material index
    /// is sticky: it applies to every later object of this group, including
    /// nested groups and transforms, which start from it; changes inside a
    /// nested group stay there.
    pub(super) fn group(&mut self, kw: Token<'a>, inherited: Current) -> Result<Node> {
        self.open(kw)?;
        let n = self.count("numObjects")?;
        let mut current = inherited;
        let mut children = Vec::new();
        loop {
            let t = self.next();
            match t {
                Some(t) if t.kind == Kind::Close => {
                    if children.len() < n {
                        return Err(self.too_few(t, n, children.len(), "object", "numObjects"));
                    }
                    return Ok(Node::Group(children));
                }
                // Like the course's reader, nothing but `}` may follow the
                // last object.
                _ if children.len() == n => match t.filter(|t| is_object(*t)) {
                    Some(t) => return Err(self.too_many(t, n, "object", "numObjects")),
                    None => return Err(self.error(t, closing(kw))),
                },
                Some(t) if t.is("MaterialIndex") => {
                    let (i, tok) = self.non_negative("a material index")?;
                    self.material_index(i, tok)?;
                    current = Some(i);
                }
                Some(t) if is_object(t) => children.push(self.object(t, current)?),
                _ => {
                    let expected = "an object (Sphere, Plane, Triangle, TriangleMesh, Group, \
                                    Transform, KeyframedTransform)";
                    return Err(self.error(
                        t,
                        format!("{expected}, 'MaterialIndex', or {}", closing(kw)),
                    ));
                }
            }
        }
    }

    /// Any object; `kw` is its keyword (checked by the caller).
    fn object(&mut self, kw: Token<'a>, material: Current) -> Result<Node> {
        let shape = match kw.text {
            "Group" | "Transform" | "KeyframedTransform" => {
                if self.depth == MAX_DEPTH {
                    let expected = format!("at most {MAX_DEPTH} nested Groups and Transforms");
                    return Err(self.error(Some(kw), expected));
                }
                self.depth += 1;
                let node = match kw.text {
                    "Group" => self.group(kw, material),
                    "Transform" => self.transform(kw, material),
                    _ => self.keyframed(kw, material),
                };
                self.depth -= 1;
                return node;
            }
            "Sphere" => self.sphere(kw)?,
            "Plane" => self.plane(kw)?,
            "Triangle" => self.triangle(kw)?,
            _ => self.mesh(kw)?,
        };
        Ok(Node::Shape { shape, material })
    }

    /// `Transform { command* object }`.
    fn transform(&mut self, kw: Token<'a>, material: Current) -> Result<Node> {
        self.open(kw)?;
        let mut matrix = glam::DMat4::IDENTITY;
        let child = loop {
            let t = self.next();
            match t {
                Some(t) if is_object(t) => break self.object(t, material)?,
                Some(t) => match self.transform_command(t)? {
                    Some(m) => matrix *= m,
                    None => {
                        return Err(
                            self.error(Some(t), "a transform command or the object to transform")
                        )
                    }
                },
                None => return Err(self.error(t, "a transform command or the object to transform")),
            }
        };
        match self.next() {
            Some(t) if t.kind == Kind::Close => {}
            other => {
                let expected = format!("{} (a Transform holds one object)", closing(kw));
                return Err(self.error(other, expected));
            }
        }
        // Rendering maps rays through the inverse; a singular or overflowing
        // matrix would fill the image with NaN. Rendering rounds the matrix to
        // f32 where it keeps a transform, so that one must be invertible too.
        let det = matrix.as_mat4().as_dmat4().determinant();
        if !matrix.as_mat4().is_finite() || det == 0.0 || !det.is_finite() {
            return Err(self.error_found(
                Some(kw),
                "an invertible transform",
                "'Transform' with a singular matrix",
            ));
        }
        Ok(Node::Transform {
            matrix,
            child: Box::new(child),
        })
    }

    /// `KeyframedTransform { numKeyframes n Keyframe{..}* object }`: the
    /// object moves through the keyframes' poses (motion blur). Keyframe
    /// times must strictly increase.
    fn keyframed(&mut self, kw: Token<'a>, material: Current) -> Result<Node> {
        self.open(kw)?;
        match self.next() {
            Some(t) if t.is("numKeyframes") => {}
            other => return Err(self.error(other, "'numKeyframes'")),
        }
        let (motion, n) = self.keyframe_list()?;
        let child = match self.next() {
            Some(t) if is_object(t) => self.object(t, material)?,
            Some(t) if t.is("Keyframe") => {
                return Err(self.too_many(t, n, "keyframe", "numKeyframes"))
            }
            other => {
                return Err(self.error(
                    other,
                    "the object to move (a KeyframedTransform holds one object)",
                ))
            }
        };
        match self.next() {
            Some(t) if t.kind == Kind::Close => {}
            other => {
                let expected = format!("{} (a KeyframedTransform holds one object)", closing(kw));
                return Err(self.error(other, expected));
            }
        }
        Ok(Node::Moving {
            motion: Arc::new(motion),
            child: Box::new(child),
        })
    }

    /// After `numKeyframes`: the count and that many `Keyframe` blocks, times
    /// strictly increasing (a `KeyframedTransform`'s and a camera's). Returns
    /// the motion and the count.
    pub(super) fn keyframe_list(&mut self) -> Result<(Motion, usize)> {
        let (n, n_tok) = self.non_negative("a count after 'numKeyframes'")?;
        if n == 0 {
            return Err(self.error(Some(n_tok), "at least 1 keyframe"));
        }
        let mut keys: Vec<Keyframe> = Vec::new();
        while keys.len() < n {
            match self.next() {
                Some(t) if t.is("Keyframe") => {
                    let (key, time_tok) = self.keyframe(t)?;
                    if let Some(prev) = keys.last() {
                        if key.time <= prev.time {
                            let expected =
                                format!("a keyframe time after the previous one ({})", prev.time);
                            return Err(self.error(Some(time_tok), expected));
                        }
                    }
                    keys.push(key);
                }
                other => {
                    let expected = format!("{} (numKeyframes {n})", plural(n, "keyframe"));
                    let what = other.map_or("the end of the file".to_string(), |t| quote(t.text));
                    let found = format!("{what} after {}", plural(keys.len(), "keyframe"));
                    return Err(self.error_found(other, expected, found));
                }
            }
        }
        let motion = Motion::new(keys).expect("checked: at least one key, increasing times");
        Ok((motion, n))
    }

    /// `Keyframe { time t [translate V] [rotate axis degrees] [scale V] }`;
    /// returns the keyframe and its time token (for ordering errors).
    fn keyframe(&mut self, kw: Token<'a>) -> Result<(Keyframe, Token<'a>)> {
        let mut time = None;
        let mut key = Keyframe::identity(0.0);
        let close = self.fields(kw, &["time", "translate", "rotate", "scale"], |p, f| {
            match f.text {
                "time" => time = Some(p.number()?),
                "translate" => key.translation = p.vec3()?.0,
                "rotate" => {
                    let (axis, toks) = p.vec3()?;
                    let degrees = p.number()?.0;
                    let axis = axis.as_dvec3();
                    if axis.length_squared() == 0.0 {
                        return Err(p.error_found(
                            Some(toks[0]),
                            "a non-zero rotation axis",
                            vec_text(&toks),
                        ));
                    }
                    key.rotation =
                        Quat::from_axis_angle(axis.normalize().as_vec3(), degrees.to_radians());
                }
                _ => {
                    let (v, toks) = p.vec3()?;
                    // A zero scale squashes the object flat and makes the
                    // inverse pose infinite.
                    if let Some(i) = (0..3).find(|&i| v[i] == 0.0) {
                        return Err(p.error(Some(toks[i]), "a non-zero scale"));
                    }
                    key.scale = v;
                }
            }
            Ok(())
        })?;
        let (t, tok) = self.require(time, close, "time", kw)?;
        key.time = t;
        Ok((key, tok))
    }

    /// `Sphere { center V radius r }`, `r > 0`.
    fn sphere(&mut self, kw: Token<'a>) -> Result<ShapeDesc> {
        let (mut center, mut radius) = (None, None);
        let close = self.fields(kw, &["center", "radius"], |p, f| {
            match f.text {
                "center" => center = Some(p.dvec3()?.0),
                _ => radius = Some(p.number()?),
            }
            Ok(())
        })?;
        let center = self.require(center, close, "center", kw)?;
        let (radius, tok) = self.require(radius, close, "radius", kw)?;
        if radius <= 0.0 {
            return Err(self.error(Some(tok), "a positive radius"));
        }
        Ok(ShapeDesc::Sphere { center, radius })
    }

    /// `Plane { normal V offset d }`: the points `p` with `normal · p = d`.
    fn plane(&mut self, kw: Token<'a>) -> Result<ShapeDesc> {
        let (mut normal, mut offset) = (None, None);
        let close = self.fields(kw, &["normal", "offset"], |p, f| {
            match f.text {
                "normal" => normal = Some(p.vec3()?),
                _ => offset = Some(p.number64()?.0),
            }
            Ok(())
        })?;
        let (normal, toks) = self.require(normal, close, "normal", kw)?;
        let offset = self.require(offset, close, "offset", kw)?;
        if normal.as_dvec3().length_squared() == 0.0 {
            return Err(self.error_found(
                Some(toks[0]),
                "a non-zero plane normal",
                vec_text(&toks),
            ));
        }
        Ok(ShapeDesc::Plane { normal, offset })
    }

    /// `Triangle { vertex0 V vertex1 V vertex2 V }`. Degenerate triangles are
    /// allowed: they are harmless, and meshes are full of them.
    fn triangle(&mut self, kw: Token<'a>) -> Result<ShapeDesc> {
        let mut v: [Option<DVec3>; 3] = [None; 3];
        let names = ["vertex0", "vertex1", "vertex2"];
        let close = self.fields(kw, &names, |p, f| {
            let i = names.iter().position(|n| *n == f.text).unwrap_or(0);
            v[i] = Some(p.dvec3()?.0);
            Ok(())
        })?;
        let mut out = [DVec3::ZERO; 3];
        for i in 0..3 {
            out[i] = self.require(v[i], close, names[i], kw)?;
        }
        Ok(ShapeDesc::Triangle(out))
    }

    /// `TriangleMesh { obj_file NAME [smooth] }`, NAME relative to the
    /// scene's folder: an OBJ, PLY or glTF file (by its extension, see
    /// `format::load_mesh_file`). `smooth` shades it with vertex normals,
    /// computed (angle-weighted) where the file has none. Each file is
    /// loaded once per scene and shared.
    fn mesh(&mut self, kw: Token<'a>) -> Result<ShapeDesc> {
        let mut name = None;
        let mut smooth = false;
        let close = self.fields(kw, &["obj_file", "smooth"], |p, f| {
            if f.text == "smooth" {
                smooth = true;
            } else {
                name = Some(p.word("a mesh file name (.obj, .ply, .gltf or .glb)")?);
            }
            Ok(())
        })?;
        let name = self.require(name, close, "obj_file", kw)?;
        let path = self.file.parent().unwrap_or(Path::new("")).join(name.text);
        let mesh = match self.meshes.get(&path) {
            Some(mesh) => Arc::clone(mesh),
            None => {
                let loaded = match self.gate {
                    Some(gate) => gate(&path)
                        .map_err(LoadError::Io)
                        .and_then(|p| crate::format::load_mesh_file(&p)),
                    None => crate::format::load_mesh_file(&path),
                };
                let mesh = match loaded {
                    Ok(m) => Arc::new(m),
                    Err(LoadError::Io(e)) => {
                        // The token may be shortened by `quote`; the path it
                        // resolved to is shown in full, so the user sees
                        // where glint looked.
                        let found = format!(
                            "{} ({}) at {}",
                            quote(name.text),
                            io_reason(&e),
                            path.display()
                        );
                        let expected = crate::format::MeshKind::of(&path)
                            .map_or("a readable OBJ file", |k| k.expected());
                        return Err(self.error_found(Some(name), expected, found));
                    }
                    Err(LoadError::Parse(e)) => return Err(e),
                };
                self.meshes.insert(path, Arc::clone(&mesh));
                mesh
            }
        };
        if smooth && mesh.normals.is_empty() {
            return Ok(ShapeDesc::Mesh(Arc::new(mesh.with_computed_normals())));
        }
        Ok(ShapeDesc::Mesh(mesh))
    }
}

/// True for a word that starts an object.
fn is_object(t: Token<'_>) -> bool {
    t.kind == Kind::Word && OBJECTS.contains(&t.text)
}
