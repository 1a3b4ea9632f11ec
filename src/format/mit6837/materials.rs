//! The `Materials` block: Phong materials and the solid textures that blend
//! two earlier entries of the table.

use super::cursor::{closing, Parser};
use super::lexer::{Kind, Token};
use super::Result;
use crate::limits::MAX_OCTAVES;
use crate::math::Mat4;
use crate::scene::{Material, Phong, TextureKind};

/// The keywords of a material table entry.
const KINDS: [&str; 6] = [
    "Material",
    "PhongMaterial",
    "Checkerboard",
    "Noise",
    "Marble",
    "Wood",
];

impl<'a> Parser<'a> {
    /// `Materials { numMaterials n entry* }`; also records the table's size.
    pub(super) fn materials(&mut self, kw: Token<'a>) -> Result<Vec<Material>> {
        self.open(kw)?;
        let n = self.count("numMaterials")?;
        let mut table = Vec::new();
        loop {
            let t = self.next();
            match t {
                Some(t) if t.kind == Kind::Close => {
                    if table.len() < n {
                        return Err(self.too_few(t, n, table.len(), "material", "numMaterials"));
                    }
                    self.material_count = Some(table.len());
                    return Ok(table);
                }
                Some(t) if t.kind == Kind::Word && KINDS.contains(&t.text) => {
                    if table.len() == n {
                        return Err(self.too_many(t, n, "material", "numMaterials"));
                    }
                    let m = match t.text {
                        "Material" | "PhongMaterial" => Material::Phong(self.phong(t)?),
                        _ => self.texture(t, table.len())?,
                    };
                    table.push(m);
                }
                _ if table.len() == n => return Err(self.error(t, closing(kw))),
                _ => {
                    let list =
                        "a material (Material, PhongMaterial, Checkerboard, Noise, Marble, Wood)";
                    return Err(self.error(t, format!("{list}, or {}", closing(kw))));
                }
            }
        }
    }

    /// `Material` or `PhongMaterial`: both take every Phong field, any order;
    /// missing fields come from [`Phong::default`].
    fn phong(&mut self, kw: Token<'a>) -> Result<Phong> {
        let mut m = Phong::default();
        let names = [
            "diffuseColor",
            "specularColor",
            "exponent",
            "reflectiveColor",
            "transparentColor",
            "indexOfRefraction",
            "glossiness",
            "emittedColor",
        ];
        self.fields(kw, &names, |p, f| {
            match f.text {
                "diffuseColor" => m.diffuse = p.color()?,
                "specularColor" => m.specular = p.color()?,
                // Radiance; the same range as every colour.
                "emittedColor" => m.emission = p.color()?,
                // At most 1: a ray's weight never grows down the tree, so
                // 64 bounces cannot overflow a pixel.
                "reflectiveColor" => m.reflective = p.vec3_within(1.0, "a reflectivity")?,
                "transparentColor" => m.transparent = p.vec3_within(1.0, "a transparency")?,
                // A negative exponent makes the highlight infinite where N·H = 0.
                "exponent" => m.exponent = p.number_where(|v| v >= 0.0, "an exponent >= 0")?,
                "glossiness" => {
                    m.glossiness =
                        p.number_where(|v| (0.0..=1.0).contains(&v), "a glossiness from 0 to 1")?
                }
                // Refraction divides by the index.
                _ => m.ior = p.number_where(|v| v > 0.0, "a positive index of refraction")?,
            }
            Ok(())
        })?;
        Ok(m)
    }

    /// A texture: `[Transform {..}]`, two `materialIndex` entries naming
    /// materials before `index` (its own position), and the pattern's numbers.
    fn texture(&mut self, kw: Token<'a>, index: usize) -> Result<Material> {
        let names: &[&str] = match kw.text {
            "Checkerboard" => &["Transform", "materialIndex"],
            "Noise" => &["Transform", "materialIndex", "octaves"],
            _ => &[
                "Transform",
                "materialIndex",
                "octaves",
                "frequency",
                "amplitude",
            ],
        };
        let mut transform = Mat4::IDENTITY;
        let mut ab: Vec<usize> = Vec::new();
        let (mut octaves, mut frequency, mut amplitude) = (None, None, None);
        let close = self.fields_with(kw, names, &[("materialIndex", 2)], |p, f| {
            match f.text {
                "Transform" => transform = p.texture_transform(f)?,
                "materialIndex" => ab.push(p.earlier_material(index)?),
                "octaves" => octaves = Some(p.octaves()?),
                "frequency" => frequency = Some(p.number()?.0),
                _ => amplitude = Some(p.number()?.0),
            }
            Ok(())
        })?;
        let [a, b] = ab[..] else {
            return Err(self.error(
                Some(close),
                format!("two 'materialIndex' entries in {}", kw.text),
            ));
        };
        let kind = match kw.text {
            "Checkerboard" => TextureKind::Checkerboard,
            "Noise" => TextureKind::Noise {
                octaves: self.require(octaves, close, "octaves", kw)?,
            },
            _ => {
                let octaves = self.require(octaves, close, "octaves", kw)?;
                let frequency = self.require(frequency, close, "frequency", kw)?;
                let amplitude = self.require(amplitude, close, "amplitude", kw)?;
                match kw.text {
                    "Marble" => TextureKind::Marble {
                        octaves,
                        frequency,
                        amplitude,
                    },
                    _ => TextureKind::Wood {
                        octaves,
                        frequency,
                        amplitude,
                    },
                }
            }
        };
        Ok(Material::Texture {
            kind,
            transform,
            a,
            b,
        })
    }

    /// `Transform { commands }` inside a texture: no child object.
    fn texture_transform(&mut self, kw: Token<'a>) -> Result<Mat4> {
        self.open(kw)?;
        let mut m = glam::DMat4::IDENTITY;
        loop {
            let t = self.next();
            match t {
                Some(t) if t.kind == Kind::Close => break,
                Some(t) => match self.transform_command(t)? {
                    Some(x) => m *= x,
                    None => {
                        return Err(
                            self.error(Some(t), format!("a transform command, or {}", closing(kw)))
                        )
                    }
                },
                None => {
                    return Err(self.error(t, format!("a transform command, or {}", closing(kw))))
                }
            }
        }
        // Composed in f64; textures look points up in f32.
        let m = m.as_mat4();
        if !m.is_finite() {
            return Err(self.error(Some(kw), "a transform with finite entries"));
        }
        Ok(m)
    }

    /// A texture's `materialIndex`: it must name an entry defined before it.
    fn earlier_material(&mut self, index: usize) -> Result<usize> {
        let (i, tok) = self.non_negative("a material index")?;
        if i < index {
            return Ok(i);
        }
        let expected = match index {
            0 => "a material defined earlier (this texture is the first entry)".to_owned(),
            _ => format!("the index of an earlier material (0 to {})", index - 1),
        };
        Err(self.error(Some(tok), expected))
    }

    /// A texture's octave count, 0 to [`MAX_OCTAVES`]: each octave is one
    /// more noise lookup per shading point, so 2e9 of them hang a render.
    fn octaves(&mut self) -> Result<u32> {
        let (n, tok) = self.non_negative("an octave count")?;
        u32::try_from(n)
            .ok()
            .filter(|&n| n <= MAX_OCTAVES)
            .ok_or_else(|| {
                self.error(
                    Some(tok),
                    format!("an octave count from 0 to {MAX_OCTAVES}"),
                )
            })
    }

    /// A number satisfying `ok`, else an error at it expecting `what`.
    pub(super) fn number_where(&mut self, ok: impl Fn(f32) -> bool, what: &str) -> Result<f32> {
        let (v, tok) = self.number()?;
        if ok(v) {
            Ok(v)
        } else {
            Err(self.error(Some(tok), what))
        }
    }

    /// Checks a `MaterialIndex` against the table, or defers the check until
    /// the `Materials` block has been read.
    pub(super) fn material_index(&mut self, i: usize, tok: Token<'a>) -> Result<()> {
        match self.material_count {
            Some(n) if i >= n => {
                let expected = match n {
                    0 => "no MaterialIndex (the scene defines no materials)".to_owned(),
                    _ => format!("a material index from 0 to {} (numMaterials {n})", n - 1),
                };
                Err(self.error(Some(tok), expected))
            }
            Some(_) => Ok(()),
            None => {
                self.pending_indices.push((i, tok));
                Ok(())
            }
        }
    }

    /// Runs the deferred `MaterialIndex` checks once the table's size is known.
    pub(super) fn check_pending_indices(&mut self) -> Result<()> {
        for (i, tok) in std::mem::take(&mut self.pending_indices) {
            self.material_index(i, tok)?;
        }
        Ok(())
    }
}
