//! Floating-point error analysis helpers (pbrt-v3 §3.9, pbrt-v4 §6.8).
//!
//! Every f32 operation rounds its exact result by a relative error of at
//! most `ε = 2⁻²⁴` (half an ulp). A chain of `n` such roundings stays within
//! the factor `(1 ± ε)ⁿ`, which is bounded by `1 ± γ(n)` with
//! `γ(n) = n·ε / (1 − n·ε)`: the constant of every error bound in `shape`.

/// Half an ulp of 1: the largest relative error of one rounded f32 operation.
pub const MACHINE_EPSILON: f32 = f32::EPSILON * 0.5;

/// `γ(n) = n·ε / (1 − n·ε)`: bounds the relative error of `n` successive
/// rounded f32 operations (Higham's bound, as in pbrt).
#[inline]
pub const fn gamma(n: u32) -> f32 {
    let ne = n as f32 * MACHINE_EPSILON;
    ne / (1.0 - ne)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_is_slightly_above_n_epsilon() {
        assert!(gamma(1) > MACHINE_EPSILON);
        assert!(gamma(7) > 7.0 * MACHINE_EPSILON && gamma(7) < 7.001 * MACHINE_EPSILON);
        assert!(gamma(3) < gamma(5));
    }
}
