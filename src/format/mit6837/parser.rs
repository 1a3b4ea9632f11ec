//! The top level of a scene file, the cameras, lights and background.

use super::cursor::{closing, ordinal, plural, vec_text, Parser};
use super::lexer::{Kind, Token};
use super::Result;
use crate::format::diagnostic::quote;
use crate::math::Vec3;
use crate::scene::{Background, Camera, Light, Scene};
use std::path::{Path, PathBuf};

/// Parses a whole scene; `file` is used in messages and to resolve meshes.
pub(crate) fn parse(src: &str, file: &Path) -> Result<Scene> {
    parse_with_meshes(src, file).map(|(scene, _)| scene)
}

/// [`parse`], and the paths of the mesh files the scene read.
pub(crate) fn parse_with_meshes(src: &str, file: &Path) -> Result<(Scene, Vec<PathBuf>)> {
    let mut p = Parser::new(src, file);
    let mut camera = None;
    let mut lights: Option<Vec<Light>> = None;
    let mut background = None;
    let mut materials = None;
    let mut root = None;
    while let Some(t) = p.next() {
        match (t.kind, t.text) {
            (Kind::Word, "OrthographicCamera" | "PerspectiveCamera") => {
                if camera.is_some() {
                    let found = format!("a second camera {}", quote(t.text));
                    return Err(p.error_found(Some(t), "one camera", found));
                }
                camera = Some(p.camera(t)?);
            }
            (Kind::Word, "Lights") => {
                p.once(lights.is_some(), t)?;
                lights = Some(p.lights(t)?);
            }
            (Kind::Word, "Background") => {
                p.once(background.is_some(), t)?;
                background = Some(p.background(t)?);
            }
            (Kind::Word, "Materials") => {
                p.once(materials.is_some(), t)?;
                materials = Some(p.materials(t)?);
                p.check_pending_indices()?;
            }
            (Kind::Word, "Group") => {
                p.once(root.is_some(), t)?;
                root = Some(p.group(t, None)?);
            }
            _ => {
                let expected = "a block (OrthographicCamera, PerspectiveCamera, Lights, \
                                Background, Materials, Group)";
                return Err(p.error(Some(t), expected));
            }
        }
    }
    let camera = camera
        .ok_or_else(|| p.error(None, "a camera (OrthographicCamera or PerspectiveCamera)"))?;
    let root = root.ok_or_else(|| p.error(None, "a top-level Group"))?;
    if materials.is_none() {
        p.material_count = Some(0);
        p.check_pending_indices()?;
    }
    let lights = lights.unwrap_or_default();
    let mut background = background.unwrap_or_default();
    // The course's reader does this so that light-less scenes (assignment 1)
    // show each material's diffuse colour, and it overrides any ambientLight.
    if lights.is_empty() {
        background.ambient = Vec3::ONE;
    }
    let mut meshes: Vec<PathBuf> = p.meshes.into_keys().collect();
    meshes.sort();
    let scene = Scene {
        camera,
        lights,
        background,
        materials: materials.unwrap_or_default(),
        root,
    };
    Ok((scene, meshes))
}

impl<'a> Parser<'a> {
    /// Rejects a second block of a kind that may appear only once.
    fn once(&self, present: bool, t: Token<'a>) -> Result<()> {
        if !present {
            return Ok(());
        }
        let expected = format!("at most one {} block", t.text);
        Err(self.error_found(Some(t), expected, format!("a second {}", quote(t.text))))
    }

    /// `OrthographicCamera {center direction up size}` or
    /// `PerspectiveCamera {center direction up angle}`, fields in any order.
    fn camera(&mut self, kw: Token<'a>) -> Result<Camera> {
        let ortho = kw.text == "OrthographicCamera";
        let last = if ortho { "size" } else { "angle" };
        let (mut center, mut direction, mut up, mut extent) = (None, None, None, None);
        let close = self.fields(kw, &["center", "direction", "up", last], |p, f| {
            match f.text {
                "center" => center = Some(p.vec3()?.0),
                "direction" => direction = Some(p.vec3()?),
                "up" => up = Some(p.vec3()?),
                _ => extent = Some(p.number()?),
            }
            Ok(())
        })?;
        let center = self.require(center, close, "center", kw)?;
        let (direction, dir_toks) = self.require(direction, close, "direction", kw)?;
        let (up, up_toks) = self.require(up, close, "up", kw)?;
        let (extent, extent_tok) = self.require(extent, close, last, kw)?;
        let d = direction.as_dvec3();
        let u = up.as_dvec3();
        if d.length_squared() == 0.0 {
            return Err(self.error_found(
                Some(dir_toks[0]),
                "a non-zero camera direction",
                vec_text(&dir_toks),
            ));
        }
        if u.length_squared() == 0.0 {
            return Err(self.error_found(
                Some(up_toks[0]),
                "a non-zero up vector",
                vec_text(&up_toks),
            ));
        }
        // Computed in f64 so that large but finite inputs cannot overflow.
        if d.cross(u).length() <= 1e-9 * d.length() * u.length() {
            let expected = "an up vector not parallel to the camera direction";
            return Err(self.error_found(Some(up_toks[0]), expected, vec_text(&up_toks)));
        }
        if ortho {
            if extent <= 0.0 {
                return Err(self.error(Some(extent_tok), "a positive size"));
            }
            return Ok(Camera::Orthographic {
                center,
                direction,
                up,
                size: extent,
            });
        }
        if !(extent > 0.0 && extent < 180.0) {
            return Err(self.error(
                Some(extent_tok),
                "an angle between 0 and 180 degrees (exclusive)",
            ));
        }
        Ok(Camera::Perspective {
            center,
            direction,
            up,
            angle_deg: extent,
        })
    }

    /// `Lights { numLights n (DirectionalLight{..} | PointLight{..})* }`.
    fn lights(&mut self, kw: Token<'a>) -> Result<Vec<Light>> {
        self.open(kw)?;
        let n = self.count("numLights")?;
        let mut lights = Vec::new();
        loop {
            let t = self.next();
            match t {
                Some(t) if t.kind == Kind::Close => {
                    return match lights.len() < n {
                        true => Err(self.too_few(t, n, lights.len(), "light", "numLights")),
                        false => Ok(lights),
                    };
                }
                Some(t) if t.is("DirectionalLight") || t.is("PointLight") => {
                    if lights.len() == n {
                        return Err(self.too_many(t, n, "light", "numLights"));
                    }
                    lights.push(self.light(t)?);
                }
                _ if lights.len() == n => return Err(self.error(t, closing(kw))),
                _ => {
                    return Err(self.error(
                        t,
                        format!("'DirectionalLight', 'PointLight', or {}", closing(kw)),
                    ))
                }
            }
        }
    }

    /// One light block; PointLight's attenuation defaults to (1, 0, 0).
    fn light(&mut self, kw: Token<'a>) -> Result<Light> {
        let directional = kw.text == "DirectionalLight";
        let names: &[&str] = if directional {
            &["direction", "color"]
        } else {
            &["position", "color", "attenuation"]
        };
        let (mut place, mut color, mut attenuation) = (None, None, None);
        let close = self.fields(kw, names, |p, f| {
            match f.text {
                "color" => color = Some(p.color()?),
                "attenuation" => {
                    attenuation = Some(p.vec3_within(f32::MAX, "an attenuation coefficient")?)
                }
                _ => place = Some(p.vec3()?),
            }
            Ok(())
        })?;
        let (place, place_toks) = self.require(place, close, names[0], kw)?;
        let color = self.require(color, close, "color", kw)?;
        // A directional light without a direction would light nothing.
        if directional && place.as_dvec3().length_squared() == 0.0 {
            return Err(self.error_found(
                Some(place_toks[0]),
                "a non-zero light direction",
                vec_text(&place_toks),
            ));
        }
        Ok(match directional {
            true => Light::Directional {
                direction: place,
                color,
            },
            false => Light::Point {
                position: place,
                color,
                attenuation: attenuation.unwrap_or(Vec3::X),
            },
        })
    }

    /// `Background { [color V] [ambientLight V] }`, defaults from [`Background::default`].
    fn background(&mut self, kw: Token<'a>) -> Result<Background> {
        let mut bg = Background::default();
        self.fields(kw, &["color", "ambientLight"], |p, f| {
            let v = p.color()?;
            match f.text {
                "color" => bg.color = v,
                _ => bg.ambient = v,
            }
            Ok(())
        })?;
        Ok(bg)
    }

    /// "expected 2 objects (numObjects 2), found '}' after 1 object".
    pub(super) fn too_few(
        &self,
        close: Token<'a>,
        n: usize,
        got: usize,
        item: &str,
        keyword: &str,
    ) -> crate::format::ParseError {
        let expected = format!("{} ({keyword} {n})", plural(n, item));
        self.error_found(
            Some(close),
            expected,
            format!("'}}' after {}", plural(got, item)),
        )
    }

    /// "expected 2 objects (numObjects 2), found a 3rd 'Sphere'".
    pub(super) fn too_many(
        &self,
        extra: Token<'a>,
        n: usize,
        item: &str,
        keyword: &str,
    ) -> crate::format::ParseError {
        let expected = format!("{} ({keyword} {n})", plural(n, item));
        self.error_found(
            Some(extra),
            expected,
            format!("a {} {}", ordinal(n + 1), quote(extra.text)),
        )
    }
}
