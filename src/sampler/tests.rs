use super::*;

const KINDS: [SamplerKind; 4] = [
    SamplerKind::Uniform(GridLayout::CENTERS),
    SamplerKind::Random,
    SamplerKind::Jittered,
    SamplerKind::Sobol,
];

/// The first `dims` values of a stream, alternating 2-D and 1-D requests.
fn values(s: &Sampler, pixel: (u32, u32), index: u32, dims: u32) -> Vec<f32> {
    let mut st = s.stream(pixel, index);
    let mut out = Vec::new();
    for d in 0..dims {
        if d % 2 == 0 {
            let v = st.next_2d();
            out.extend([v.x, v.y]);
        } else {
            out.push(st.next_1d());
        }
    }
    out
}

#[test]
fn values_are_a_pure_function_of_seed_pixel_index_dimension() {
    for kind in KINDS {
        let s = Sampler::new(kind, 16, 7);
        // Visiting pixels and indices in two different orders (as two
        // thread schedules would) gives the same values.
        let mut forward = Vec::new();
        for j in 0..4 {
            for i in 0..4 {
                for k in 0..16 {
                    forward.push(values(&s, (i, j), k, 6));
                }
            }
        }
        for j in (0..4).rev() {
            for i in (0..4).rev() {
                for k in (0..16).rev() {
                    let idx = (j * 4 + i) * 16 + k;
                    assert_eq!(values(&s, (i, j), k, 6), forward[idx as usize], "{kind:?}");
                }
            }
        }
        // A copy of the sampler gives the same values.
        let copy = s;
        assert_eq!(values(&copy, (3, 2), 5, 6), values(&s, (3, 2), 5, 6));
        for v in forward.iter().flatten() {
            assert!((0.0..1.0).contains(v), "{kind:?}: {v}");
        }
        if kind != SamplerKind::Uniform(GridLayout::CENTERS) {
            // The seed, the pixel and the index all change the values.
            let other_seed = Sampler::new(kind, 16, 8);
            assert_ne!(values(&other_seed, (1, 1), 3, 6), values(&s, (1, 1), 3, 6));
            assert_ne!(values(&s, (1, 2), 3, 6), values(&s, (2, 1), 3, 6));
            assert_ne!(values(&s, (1, 1), 3, 6), values(&s, (1, 1), 4, 6));
        }
    }
}

/// Counts of samples per cell of an `nx × ny` grid.
fn cell_counts(points: &[Vec2], nx: u32, ny: u32) -> Vec<u32> {
    let mut c = vec![0; (nx * ny) as usize];
    for p in points {
        let (x, y) = ((p.x * nx as f32) as u32, (p.y * ny as f32) as u32);
        c[(y * nx + x) as usize] += 1;
    }
    c
}

#[test]
fn jittered_puts_exactly_one_sample_per_stratum() {
    for spp in [1, 4, 9, 16, 36, 6, 7, 12] {
        let s = Sampler::new(SamplerKind::Jittered, spp, 3);
        let (kx, ky) = s.grid();
        assert_eq!(kx * ky, spp);
        for pixel in [(0, 0), (5, 9), (123, 4)] {
            // Dimension 0 (the pixel position) and a later 2-D dimension.
            for skip in [0, 3] {
                let pts: Vec<Vec2> = (0..spp)
                    .map(|k| {
                        let mut st = s.stream(pixel, k);
                        for _ in 0..skip {
                            st.next_1d();
                        }
                        st.next_2d()
                    })
                    .collect();
                assert!(
                    cell_counts(&pts, kx, ky).iter().all(|&c| c == 1),
                    "spp {spp} pixel {pixel:?} dim {skip}"
                );
            }
            // A 1-D dimension: one sample per 1/spp interval.
            let xs: Vec<Vec2> = (0..spp)
                .map(|k| {
                    let mut st = s.stream(pixel, k);
                    st.next_2d();
                    Vec2::new(st.next_1d(), 0.0)
                })
                .collect();
            assert!(cell_counts(&xs, spp, 1).iter().all(|&c| c == 1));
        }
    }
}

#[test]
fn jittered_is_not_the_uniform_grid() {
    let s = Sampler::new(SamplerKind::Jittered, 16, 1);
    let u = Sampler::new(SamplerKind::Uniform(GridLayout::CENTERS), 16, 1);
    let differs = (0..16).filter(|&k| values(&s, (2, 3), k, 1) != values(&u, (2, 3), k, 1));
    assert!(differs.count() >= 15);
}

#[test]
fn sobol_pixel_positions_are_stratified_at_powers_of_two() {
    let s = Sampler::new(SamplerKind::Sobol, 64, 11);
    for pixel in [(0, 0), (17, 3)] {
        let pts: Vec<Vec2> = (0..64).map(|k| s.stream(pixel, k).next_2d()).collect();
        for (n, nx, ny) in [(4, 2, 2), (16, 4, 4), (16, 16, 1), (64, 8, 8), (64, 1, 64)] {
            let c = cell_counts(&pts[..n], nx, ny);
            assert!(c.iter().all(|&c| c == 1), "{n} points, {nx}x{ny}: {c:?}");
        }
        // A later dimension is stratified too (padding by index scrambling).
        let pts: Vec<Vec2> = (0..16)
            .map(|k| {
                let mut st = s.stream(pixel, k);
                st.next_2d();
                st.next_1d();
                st.next_2d()
            })
            .collect();
        assert!(cell_counts(&pts, 4, 4).iter().all(|&c| c == 1));
    }
}

#[test]
fn uniform_layouts() {
    let grid = |layout, spp| -> Vec<Vec2> {
        let s = Sampler::new(SamplerKind::Uniform(layout), spp, 0);
        (0..spp).map(|k| s.stream((4, 4), k).next_2d()).collect()
    };
    assert_eq!(
        grid(GridLayout::CENTERS, 4),
        [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)].map(|(x, y)| Vec2::new(x, y))
    );
    let inset = grid(GridLayout::Inset, 4);
    assert!((inset[0] - Vec2::splat(1.0 / 3.0)).length() < 1e-7);
    assert!((inset[3] - Vec2::splat(2.0 / 3.0)).length() < 1e-7);
    assert_eq!(grid(GridLayout::CORNERS, 1), [Vec2::ZERO]);
    assert_eq!(
        Sampler::fixed(Vec2::splat(0.5)).stream((0, 0), 0).next_2d(),
        Vec2::splat(0.5)
    );
}

#[test]
fn names_round_trip() {
    for name in ["uniform", "random", "jittered", "sobol"] {
        let k: SamplerKind = name.parse().unwrap();
        assert_eq!(k.to_string(), name);
    }
    assert!("halton"
        .parse::<SamplerKind>()
        .unwrap_err()
        .to_string()
        .contains("halton"));
}

/// Sobol value of 2-D dimension `dim` of sample `index` of the pixel with
/// key `pixel_key`, straight from the definitions (the stream's hashes,
/// `owen_scramble` of the Sobol dimensions): what the streams and splits,
/// with their work shared per stream and per dimension, must give bit for
/// bit.
fn sobol_2d_definition(seed: u64, pixel_key: u64, index: u32, dim: u32) -> Vec2 {
    let prefix = hash(&[seed, pixel_key]);
    let h = hash(&[seed, pixel_key, dim as u64]);
    let (sx, sy) = ((h >> 32) as u32, mix64(h) as u32);
    let (x, y) = if dim == 1 {
        let h0 = hash_from(prefix, &[0]);
        sobol::point_2d_upper(index, h0 as u32, sx, sy)
    } else {
        sobol::point_2d(index, h as u32, sx, sy)
    };
    Vec2::new(hash::unit_from_u32(x), hash::unit_from_u32(y))
}

/// As [`sobol_2d_definition`], for 1-D dimension `dim`.
fn sobol_1d_definition(seed: u64, pixel_key: u64, index: u32, dim: u32) -> f32 {
    let h = hash(&[seed, pixel_key, dim as u64, 1]);
    let i = sobol::owen_scramble(index, h as u32);
    hash::unit_from_u32(sobol::owen_scramble(sobol::sobol_dim0(i), (h >> 32) as u32))
}

#[test]
fn sobol_streams_and_splits_give_the_definitions_values() {
    for (seed, spp) in [(0u64, 16u32), (7, 4), (0xdead_beef, 64)] {
        let s = Sampler::new(SamplerKind::Sobol, spp, seed);
        for (i, j) in [(0u32, 0u32), (3, 4), (511, 383), (70_000, 2)] {
            let key = i as u64 | (j as u64) << 32;
            for index in [0, 1, 5, spp - 1, spp + 3, 1 << 20] {
                let st = s.stream((i, j), index);
                for dim in 0..12 {
                    let want = sobol_2d_definition(seed, key, index, dim);
                    assert_eq!(st.get_2d(dim), want, "2-D dim {dim} index {index}");
                    let want = sobol_1d_definition(seed, key, index, dim);
                    assert_eq!(st.get_1d(dim), want, "1-D dim {dim} index {index}");
                }
                for (dim, n) in [(0, 3u32), (1, 4), (1, 1), (2, 16), (5, 7)] {
                    let mut st = s.stream((i, j), index);
                    st.skip_n(dim);
                    for (k, v) in st.split_2d(n).enumerate() {
                        let want = sobol_2d_definition(seed, key, index * n + k as u32, dim);
                        assert_eq!(v, want, "split dim {dim} n {n} value {k}");
                    }
                }
            }
        }
    }
}
