//! The packet walks' unit tests: every ray of every packet gets the hit its
//! own walk gets, bit for bit.

use super::*;
use crate::accel::bvh8::Bvh8;
use crate::accel::testutil::{ray, soup, sphere, terrain, terrain_ray, Rng};
use crate::math::Vec3;
use crate::primitive::Primitive;
use crate::stats::{Counters, NoStats};

/// Asserts that each ray of each packet gets, from the packet walks, the
/// closest hit (`t` and barycentrics compared as bits, and the id) and the
/// any-hit answer of the single walks; returns how many rays hit.
fn assert_packets_agree(b: &Bvh8, fb: &[Primitive], packets: &[Vec<PacketRay>]) -> usize {
    let ns = &mut NoStats;
    let bits =
        |c: Option<Closest>| c.map(|c| (c.t.to_bits(), c.id, c.bary.map(|w| w.map(f32::to_bits))));
    let mut hits = 0;
    for (k, p) in packets.iter().enumerate() {
        let mut got = [None; PACKET];
        b.closest_hit_packet(fb, p, &mut got, ns);
        let blocked = b.any_packet(fb, p, &[], ns);
        for (r, q) in p.iter().enumerate() {
            let want = b.closest_hit(fb, &q.ray, q.tmin, q.tmax, ns);
            assert_eq!(bits(got[r]), bits(want), "packet {k} ray {r}: {q:?}");
            let any = b.any(fb, &q.ray, q.tmin, q.tmax, ns);
            assert_eq!(blocked >> r & 1 != 0, any, "packet {k} ray {r}: {q:?}");
            hits += usize::from(want.is_some());
        }
        assert_eq!(blocked >> p.len(), 0, "no bits past the packet");
    }
    hits
}

fn pr(ray: crate::math::Ray, tmin: f32, tmax: f32) -> PacketRay {
    PacketRay { ray, tmin, tmax }
}

/// Random rays in random packets of 1 to 8 (incoherent: the packet walk's
/// worst case), with ranges cut short, negative and `−0` `tmin` (walked
/// alone) among them, on a soup of triangles and spheres.
#[test]
fn random_packets_agree_with_single_rays_on_a_soup() {
    let prims = soup(31, 4000);
    let b = Bvh8::new(&prims, (0..prims.len() as u32).collect());
    let mut r = Rng::new(17);
    let packets: Vec<Vec<PacketRay>> = (0..600)
        .map(|k| {
            let n = 1 + k % PACKET;
            (0..n)
                .map(|i| {
                    let (tmin, tmax) = match (k + i) % 7 {
                        0 => (0.2, 0.9),
                        1 => (-1.0, f32::INFINITY),
                        2 => (-0.0, 5.0),
                        _ => (0.0, f32::INFINITY),
                    };
                    pr(ray(&mut r), tmin, tmax)
                })
                .collect()
        })
        .collect();
    let hits = assert_packets_agree(&b, &prims, &packets);
    assert!(hits > 1000, "{hits}");
}

/// Coherent packets, as a camera makes them: 4×2 tiles of a pinhole
/// camera's rays over a height field (rays through its grid lines and
/// vertices included), and shadow rays from the hits towards one light.
#[test]
fn camera_tiles_and_shadow_rays_agree_on_a_terrain() {
    let prims = terrain();
    let b = Bvh8::new(&prims, (0..prims.len() as u32).collect());
    let eye = Vec3::new(32.0, 40.0, -20.0);
    let (w, h) = (64, 48);
    let cam = |x: usize, y: usize| {
        let d = Vec3::new(
            (x as f32 - w as f32 / 2.0) / 40.0,
            -0.8 - (y as f32) / 60.0,
            1.0,
        );
        crate::math::Ray::new(eye, d)
    };
    let mut packets = Vec::new();
    for ty in (0..h).step_by(2) {
        for tx in (0..w).step_by(4) {
            packets.push(
                (0..PACKET)
                    .map(|l| pr(cam(tx + l % 4, ty + l / 4), 0.0, f32::INFINITY))
                    .collect::<Vec<_>>(),
            );
        }
    }
    let hits = assert_packets_agree(&b, &prims, &packets);
    assert!(hits > w * h / 2, "{hits}");
    // Shadow rays of the hits, eight neighbours at a time.
    let light = Vec3::new(-20.0, 4.0, 32.0);
    let mut shadow = Vec::new();
    for p in &packets {
        for q in p {
            if let Some(c) = b.closest_hit(&prims[..], &q.ray, 0.0, f32::INFINITY, &mut NoStats) {
                let o = q.ray.at(c.t);
                let d = light - o;
                shadow.push(pr(crate::math::Ray::new(o, d), 1e-3, 1.0));
            }
        }
    }
    let packets: Vec<Vec<PacketRay>> = shadow.chunks(PACKET).map(<[_]>::to_vec).collect();
    assert_packets_agree(&b, &prims, &packets);
    // Some are blocked (the terrain's hills), not all.
    let blocked: u32 = packets
        .iter()
        .map(|p| b.any_packet(&prims[..], p, &[], &mut NoStats).count_ones())
        .sum();
    assert!(
        blocked > 20 && (blocked as usize) < shadow.len(),
        "{blocked}"
    );
    // And random rays down onto it, in packets.
    let mut r = Rng::new(3);
    let packets: Vec<Vec<PacketRay>> = (0..300)
        .map(|_| {
            (0..PACKET)
                .map(|_| pr(terrain_ray(&mut r), 0.0, f32::INFINITY))
                .collect()
        })
        .collect();
    assert_packets_agree(&b, &prims, &packets);
}

/// Items at exactly the same distance: copies of one triangle (and of one
/// sphere) with different ids, in different leaves. Each ray's walk,
/// alone or in a packet, and brute force (which tests items by id) keep
/// the smallest id.
#[test]
fn ties_go_to_the_smallest_id_in_every_walk() {
    use crate::accel::testutil::prim;
    use crate::accel::{Aggregate, Brute, Query};
    use crate::shape::{Shape, Triangle};
    let mut prims = soup(12, 2000);
    let t = Triangle::new(
        Vec3::new(-1.0, -1.0, 20.0),
        Vec3::new(3.0, -1.0, 20.0),
        Vec3::new(-1.0, 3.0, 20.0),
    );
    let copies: Vec<usize> = (0..5).map(|k| 300 * k + 7).collect();
    for &i in &copies {
        prims[i] = prim(Shape::Triangle(t));
    }
    prims.push(sphere(Vec3::new(0.0, 0.0, -20.0), 1.0));
    prims.insert(100, sphere(Vec3::new(0.0, 0.0, -20.0), 1.0));
    let ids = (0..prims.len() as u32).collect::<Vec<_>>();
    let b = Bvh8::new(&prims, ids.clone());
    let brute = Brute::new(&prims, ids);
    let mut c = Counters::default();
    // Straight at the triangle's copies from behind the soup.
    let mut packets = Vec::new();
    for k in 0..40 {
        let o = Vec3::new(0.05 * (k % 8) as f32, 0.05 * (k / 8) as f32, 30.0);
        packets.push(pr(
            crate::math::Ray::new(o, Vec3::NEG_Z),
            0.0,
            f32::INFINITY,
        ));
    }
    // And at the spheres' copies.
    for k in 0..8 {
        let o = Vec3::new(0.1 * k as f32, 0.05, -40.0);
        packets.push(pr(crate::math::Ray::new(o, Vec3::Z), 0.0, f32::INFINITY));
    }
    let packets: Vec<Vec<PacketRay>> = packets.chunks(PACKET).map(<[_]>::to_vec).collect();
    assert_packets_agree(&b, &prims, &packets);
    let (mut tris, mut spheres) = (0, 0);
    for q in packets.iter().flatten() {
        let single = b.closest(&prims[..], &q.ray, q.tmin, q.tmax, &mut NoStats);
        let want = brute.intersect(Query::new(&prims, &q.ray, q.tmin, q.tmax), &mut c);
        assert_eq!(single, want.map(|h| (h.t, h.prim)), "{q:?}");
        match single {
            Some((_, id)) if id == copies[0] as u32 => tris += 1,
            Some((_, 100)) => spheres += 1,
            _ => {}
        }
    }
    assert!(tris > 10 && spheres > 0, "{tris} {spheres}");
}

/// A tree deeper than the shallow stack serves (the chain of
/// `a_deep_tree_uses_the_deep_stack`): packets along the chain get
/// through, with the deep stack.
#[test]
fn deep_trees_take_the_deep_stack_in_packets() {
    let prims = crate::accel::testutil::chain(400);
    let b = Bvh8::new(&prims, (0..prims.len() as u32).collect());
    assert!(b.deep);
    let packets: Vec<Vec<PacketRay>> = (0..4)
        .map(|k| {
            (0..PACKET)
                .map(|l| {
                    let y = 0.1 * l as f32 + 0.2 * k as f32;
                    pr(
                        crate::math::Ray::new(Vec3::new(0.5, y, y), Vec3::X),
                        0.0,
                        f32::INFINITY,
                    )
                })
                .collect()
        })
        .collect();
    let hits = assert_packets_agree(&b, &prims, &packets);
    assert!(hits > 4 && hits < 32, "{hits}");
}

/// `skip` per ray: a ray leaving a triangle of the terrain is not blocked
/// by that triangle, in a packet as alone.
#[test]
fn packets_skip_each_rays_own_triangle() {
    let prims = terrain();
    let b = Bvh8::new(&prims, (0..prims.len() as u32).collect());
    let mut r = Rng::new(8);
    let ns = &mut NoStats;
    let mut blocked = 0;
    for _ in 0..200 {
        let (mut rays, mut skip) = (Vec::new(), Vec::new());
        for _ in 0..PACKET {
            let q = terrain_ray(&mut r);
            let Some(c) = b.closest_hit(&prims[..], &q, 0.0, f32::INFINITY, ns) else {
                continue;
            };
            let o = q.at(c.t);
            rays.push(pr(
                crate::math::Ray::new(o, r.v(-1.0, 1.0) + Vec3::Y * 0.3),
                0.0,
                50.0,
            ));
            skip.push(c.id);
        }
        let got = b.any_packet(&prims[..], &rays, &skip, ns);
        for (i, q) in rays.iter().enumerate() {
            let want = b.any_except(&prims[..], &q.ray, q.tmin, q.tmax, skip[i], ns);
            assert_eq!(got >> i & 1 != 0, want);
            blocked += usize::from(want);
        }
    }
    assert!(blocked > 50, "{blocked}");
}

/// The packet's one box test keeps every box some ray's own test (the
/// integer form the single walk runs) keeps, and the per-ray test of a
/// leaf's box keeps each ray's own boxes: random boxes, packets from one
/// origin (a camera's) and from nearby origins (shadow rays), with the
/// distance bound below each ray's own entry distance.
#[test]
fn the_packet_box_test_keeps_every_box_its_rays_keep() {
    use crate::accel::bvh8::lanes::{Lanes, W};
    use crate::accel::bvh8::node::Node;
    use crate::accel::bvh8::traverse::{Portable, RayData, ANY_OCTANT};
    let mut r = Rng::new(21);
    let (mut kept, mut packets) = (0, 0);
    #[cfg(target_arch = "x86_64")]
    let avx =
        crate::testdata::avx2_fma("the_packet_box_test_keeps_every_box_its_rays_keep (AVX part)");
    for k in 0..4000 {
        let mut node = Node::EMPTY;
        for i in 0..W {
            if r.f() < 0.9 {
                let lo = r.v(-4.0, 4.0);
                node.set(i, i as u32, lo, lo + r.v(0.0, 3.0));
            }
        }
        let base = r.v(-9.0, 9.0);
        let dir = r.v(-1.0, 1.0);
        let rays: Vec<PacketRay> = (0..PACKET)
            .map(|_| {
                let o = if k % 2 == 0 {
                    base
                } else {
                    base + r.v(-0.1, 0.1)
                };
                pr(
                    crate::math::Ray::new(o, dir + r.v(-0.02, 0.02)),
                    0.0,
                    5.0 + 20.0 * r.f(),
                )
            })
            .collect();
        let (Some(f), walked) = Frustum::new(&rays) else {
            continue;
        };
        assert_eq!(walked, 0xff);
        packets += 1;
        let mut tmax = Lanes::splat(0.0);
        for (i, q) in rays.iter().enumerate() {
            tmax[i] = q.tmax;
        }
        let (mask, dist) = f.boxes(Portable, &node, tmax.max_of(walked));
        // The AVX form answers as the portable one, bit for bit.
        #[cfg(target_arch = "x86_64")]
        if avx {
            // SAFETY: `avx` says the CPU has AVX2 and FMA.
            let a = unsafe { crate::accel::bvh8::traverse::Avx::new() };
            let (m, d) = f.boxes(a, &node, tmax.max_of(walked));
            assert_eq!(
                (m, d.to_array().map(f32::to_bits)),
                (mask, dist.to_array().map(f32::to_bits))
            );
            for c in 0..W {
                assert_eq!(
                    f.rays_into(a, &node, c, tmax),
                    f.rays_into(Portable, &node, c, tmax)
                );
            }
        }
        for (i, q) in rays.iter().enumerate() {
            let rd = RayData::new(&q.ray);
            let (own, d) = rd.boxes::<_, ANY_OCTANT, true>(
                Portable,
                &node,
                Lanes::splat(q.tmin),
                Lanes::splat(q.tmax),
            );
            assert_eq!(own & !mask, 0, "packet {k} ray {i}");
            for c in 0..W {
                if own >> c & 1 != 0 {
                    assert!(dist[c] <= d[c], "packet {k} ray {i} box {c}");
                    assert!(f.rays_into(Portable, &node, c, tmax) >> i & 1 != 0);
                    kept += 1;
                }
            }
        }
    }
    assert!(packets > 1000 && kept > 500, "{packets} {kept}");
}

/// The dominant axis of `d`, as the watertight test picks it (its `kz`).
fn dominant_axis(d: Vec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    }
}

/// Camera tiles looking along a diagonal of the terrain, so that within a
/// tile some rays' dominant axis is x and others' z: the leaf test takes
/// each axis's rays apart, and every ray still gets its own hit.
#[test]
fn packets_whose_rays_differ_in_dominant_axis_agree() {
    let prims = terrain();
    let b = Bvh8::new(&prims, (0..prims.len() as u32).collect());
    let eye = Vec3::new(-20.0, 25.0, -20.0);
    let (right, up) = (Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 1.0, 0.0));
    let cam = |x: usize, y: usize| {
        let d = Vec3::new(1.0, -0.45, 1.0)
            + right * ((x as f32 - 30.0) * 0.004 + 1e-4)
            + up * ((y as f32 - 24.0) * -0.004);
        crate::math::Ray::new(eye, d)
    };
    let (mut packets, mut mixed) = (Vec::new(), 0);
    for ty in (0..48).step_by(2) {
        for tx in (0..64).step_by(4) {
            let p: Vec<PacketRay> = (0..PACKET)
                .map(|l| pr(cam(tx + l % 4, ty + l / 4), 0.0, f32::INFINITY))
                .collect();
            let axes = p
                .iter()
                .fold(0u32, |m, q| m | 1 << dominant_axis(q.ray.dir));
            if axes.count_ones() > 1 {
                assert!(Frustum::new(&p).0.is_some(), "walked as a packet");
                mixed += 1;
            }
            packets.push(p);
        }
    }
    assert!(mixed >= 16, "{mixed}");
    let hits = assert_packets_agree(&b, &prims, &packets);
    assert!(hits > 64 * 48 / 2, "{hits}");
}

/// A ray with a NaN `tmax` in a packet: it hits nothing, as alone, and
/// the packet's other rays get their own hits (the packet's bound on its
/// `tmax` counts the NaN as `+inf`).
#[test]
fn a_nan_tmax_leaves_the_other_rays_of_a_packet_alone() {
    let prims = terrain();
    let b = Bvh8::new(&prims, (0..prims.len() as u32).collect());
    let eye = Vec3::new(32.0, 40.0, -20.0);
    let mut packets = Vec::new();
    for k in 0..64 {
        let p: Vec<PacketRay> = (0..PACKET)
            .map(|l| {
                let d = Vec3::new((l as f32 + 8.0 * (k % 8) as f32) / 40.0 - 0.8, -1.0, 1.0);
                let tmax = if l == k % PACKET {
                    f32::NAN
                } else {
                    f32::INFINITY
                };
                pr(crate::math::Ray::new(eye, d), 0.0, tmax)
            })
            .collect();
        packets.push(p);
    }
    let hits = assert_packets_agree(&b, &prims, &packets);
    assert_eq!(hits, 64 * (PACKET - 1));
}

/// The packet's `1 / d` and `origin · inv`, eight rays at a time, are the
/// single ray's (`RayData::inv_oi`) bit for bit, for tiny, zero, signed
/// zero, infinite and NaN components too.
#[test]
fn the_packet_inverse_is_the_single_rays() {
    use crate::accel::bvh8::lanes::Lanes;
    use crate::accel::bvh8::traverse::RayData;
    let mut r = Rng::new(5);
    let special = [
        0.0,
        -0.0,
        1e-20,
        -1e-19,
        1e-18,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        1e30,
        -3.5,
    ];
    for k in 0..2000 {
        let rays: Vec<crate::math::Ray> = (0..8)
            .map(|l| {
                let mut d = r.v(-2.0, 2.0);
                let mut o = r.v(-1e3, 1e3);
                if (k + l) % 3 == 0 {
                    d[(k + l) % 3] = special[(k * 7 + l) % special.len()];
                    o[l % 3] = special[(k + 3 * l) % special.len()];
                }
                crate::math::Ray::new(o, d)
            })
            .collect();
        for a in 0..3 {
            let d = Lanes::from_array(std::array::from_fn(|l| rays[l].dir[a]));
            let o = Lanes::from_array(std::array::from_fn(|l| rays[l].origin[a]));
            let (inv, oi) = RayData::inv_oi_lanes(d, o);
            for (l, q) in rays.iter().enumerate() {
                let (want_inv, want_oi) = RayData::inv_oi(q);
                assert_eq!(inv[l].to_bits(), want_inv[a].to_bits(), "{q:?}");
                assert_eq!(oi[l].to_bits(), want_oi[a].to_bits(), "{q:?}");
            }
        }
    }
}

/// The packet any-hit walk enters the far side of a node's first
/// division first, as the single walk does
/// (`any_enters_the_far_side_of_the_first_division_first`): eight
/// parallel rays towards −x above y = 0 test one leaf each where the
/// node's first division is on x, and both where it is on y (the upper,
/// near, slot first).
#[test]
fn packets_enter_the_far_side_of_the_first_division_first() {
    use crate::accel::bvh8::traverse::tests::on_two_leaves;
    use crate::accel::bvh8::traverse::{Portable, SHALLOW};
    let rays: Vec<PacketRay> = (0..PACKET)
        .map(|k| {
            let o = Vec3::new(4.0, 1.5 + 0.1 * k as f32, -1.0 + 0.25 * k as f32);
            pr(
                crate::math::Ray::new(o, Vec3::new(-1.0, 0.0, 0.0)),
                0.0,
                f32::INFINITY,
            )
        })
        .collect();
    let walk = |split: u8| {
        on_two_leaves(split, |tree| {
            let mut c = Counters::default();
            let hit = any::<_, _, _, SHALLOW>(Portable, tree, &rays, &[], &mut c);
            (c.intersection_tests, hit)
        })
    };
    assert_eq!(walk(1), (8, 0xff));
    assert_eq!(walk(2), (16, 0xff));
}
