//! Transform commands, shared by object transforms and texture transforms.
//!
//! A `Transform` block's matrix is `X1·X2·…·Xn` for its commands in the order
//! listed (column vectors): the last command acts on the object first. This
//! holds for `Matrix` too, although the course's reader pre-multiplied that one
//! (see `docs/scene-format.md`).
//!
//! Matrices are built in double precision from the numbers as written
//! (`Parser::number64`): a `Translate 100000.3 0 0` keeps its `.3`.

use super::cursor::{vec_text, Parser};
use super::lexer::{Kind, Token};
use super::Result;
use glam::{DMat4, DVec3};

impl<'a> Parser<'a> {
    /// If `kw` is a transform command, reads its arguments and returns its
    /// matrix; otherwise returns `None` and reads nothing.
    pub(super) fn transform_command(&mut self, kw: Token<'a>) -> Result<Option<DMat4>> {
        if kw.kind != Kind::Word {
            return Ok(None);
        }
        let m = match kw.text {
            "Translate" => DMat4::from_translation(self.dvec3()?.0),
            "Scale" => DMat4::from_scale(self.dvec3()?.0),
            "UniformScale" => DMat4::from_scale(DVec3::splat(self.number64()?.0)),
            "XRotate" => DMat4::from_rotation_x(self.number64()?.0.to_radians()),
            "YRotate" => DMat4::from_rotation_y(self.number64()?.0.to_radians()),
            "ZRotate" => DMat4::from_rotation_z(self.number64()?.0.to_radians()),
            "Rotate" => self.rotate(kw)?,
            "Matrix" => self.matrix(kw)?,
            _ => return Ok(None),
        };
        Ok(Some(m))
    }

    /// `Rotate x y z degrees`; the course writes it `Rotate { x y z degrees }`,
    /// so the braces are optional.
    fn rotate(&mut self, kw: Token<'a>) -> Result<DMat4> {
        let braced = self.optional_open();
        let (axis, toks) = self.dvec3()?;
        let degrees = self.number64()?.0;
        if braced {
            self.close(kw)?;
        }
        // f64, so that a huge but finite axis still normalises.
        if axis.length_squared() == 0.0 {
            return Err(self.error_found(
                Some(toks[0]),
                "a non-zero rotation axis",
                vec_text(&toks),
            ));
        }
        Ok(DMat4::from_axis_angle(
            axis.normalize(),
            degrees.to_radians(),
        ))
    }

    /// `Matrix m00 m01 … m33`: 16 numbers, row by row. The course writes it
    /// `Matrix { … }`, so the braces are optional.
    fn matrix(&mut self, kw: Token<'a>) -> Result<DMat4> {
        let braced = self.optional_open();
        let mut rows = [0.0; 16];
        for v in &mut rows {
            *v = self.number64()?.0;
        }
        if braced {
            self.close(kw)?;
        }
        // glam reads arrays column by column; the file gives rows.
        Ok(DMat4::from_cols_array(&rows).transpose())
    }

    /// Consumes a `{` if one is next.
    fn optional_open(&mut self) -> bool {
        let open = self.peek().is_some_and(|t| t.kind == Kind::Open);
        if open {
            self.next();
        }
        open
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Mat4, Vec3};
    use std::path::Path;

    /// The product of the commands in `src`, as a Transform block composes
    /// them, in f64.
    fn compose64(src: &str) -> DMat4 {
        let mut p = Parser::new(src, Path::new("t.txt"));
        let mut m = DMat4::IDENTITY;
        while let Some(t) = p.next() {
            m *= p.transform_command(t).unwrap().expect("a command");
        }
        m
    }

    fn compose(src: &str) -> Mat4 {
        compose64(src).as_mat4()
    }

    #[test]
    fn numbers_keep_every_digit_in_double_precision() {
        // f32 holds 100000.3 only to 1/128: 100000.296875.
        let m = compose64("Translate 100000.3 -7e4 0.1");
        assert_eq!(m.w_axis.x, 100000.3);
        assert_eq!(m.w_axis.y, -70000.0);
        assert_eq!(m.w_axis.z, 0.1);
        assert_ne!(m.w_axis.x, f64::from(100000.3f32));
        let m = compose64("UniformScale 1.000000001");
        assert_eq!(m.x_axis.x, 1.000000001);
    }

    fn close(a: Mat4, b: Mat4) -> bool {
        a.abs_diff_eq(b, 1e-5)
    }

    #[test]
    fn first_listed_is_applied_last() {
        let m = compose("Translate 1 0 0 Scale 2 2 2");
        assert!(m
            .transform_point3(Vec3::X)
            .abs_diff_eq(Vec3::new(3.0, 0.0, 0.0), 1e-6));
        let m = compose("Scale 2 2 2 Translate 1 0 0");
        assert!(m
            .transform_point3(Vec3::X)
            .abs_diff_eq(Vec3::new(4.0, 0.0, 0.0), 1e-6));
    }

    #[test]
    fn rotations_are_in_degrees_and_agree() {
        assert!(close(compose("Rotate 1 0 0 30"), compose("XRotate 30")));
        assert!(close(
            compose("Rotate { 0 2 0 -45 }"),
            compose("YRotate -45")
        ));
        assert!(close(compose("Rotate 0 0 1 90"), compose("ZRotate 90")));
        let p = compose("ZRotate 90").transform_point3(Vec3::X);
        assert!(p.abs_diff_eq(Vec3::Y, 1e-6));
    }

    #[test]
    fn uniform_scale_and_matrix_rows() {
        assert!(close(compose("UniformScale 3"), compose("Scale 3 3 3")));
        let m = compose("Matrix { 1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1 }");
        assert!(close(m, compose("Translate 5 6 7")));
        // Matrix composes like every other command: post-multiplied.
        let m = compose("Scale 2 2 2 Matrix 1 0 0 1 0 1 0 0 0 0 1 0 0 0 0 1");
        assert!(m
            .transform_point3(Vec3::ZERO)
            .abs_diff_eq(Vec3::new(2.0, 0.0, 0.0), 1e-6));
    }

    #[test]
    fn zero_axis_is_an_error_at_the_axis() {
        let mut p = Parser::new("Rotate 0 0 0 10", Path::new("t.txt"));
        let kw = p.next().unwrap();
        let e = p.transform_command(kw).unwrap_err();
        assert_eq!((e.line, e.col), (1, 8));
        assert_eq!(e.found, "'0 0 0'");
    }

    #[test]
    fn other_words_are_not_commands() {
        let mut p = Parser::new("Sphere {", Path::new("t.txt"));
        let kw = p.next().unwrap();
        assert_eq!(p.transform_command(kw).unwrap(), None);
        assert_eq!(p.peek().unwrap().text, "{");
    }
}
