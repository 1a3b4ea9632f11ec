//! Whole-scene tests: every block kind, defaults, material scoping, semantic
//! errors, and every scene the course shipped.

use super::parse;
use crate::format::ParseError;
use crate::math::{Mat4, Vec3};
use crate::scene::{
    AreaShape, Background, Camera, Light, Material, Node, Phong, Scene, ShapeDesc, TextureKind,
};
use glam::DVec3;
use std::path::Path;

const CAMERA: &str = "OrthographicCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 size 5 }\n";

fn scene(src: &str) -> Scene {
    parse(src, Path::new("t.txt")).unwrap_or_else(|e| panic!("{}", e.render()))
}

fn error(src: &str) -> ParseError {
    parse(src, Path::new("t.txt")).expect_err("should not parse")
}

/// The `(shape, material)` leaves in file order.
fn leaves(n: &Node, out: &mut Vec<(ShapeDesc, Option<usize>)>) {
    match n {
        Node::Group(c) => c.iter().for_each(|c| leaves(c, out)),
        Node::Transform { child, .. } | Node::Moving { child, .. } => leaves(child, out),
        Node::Shape { shape, material } => out.push((shape.clone(), *material)),
    }
}

fn materials_of(s: &Scene) -> Vec<Option<usize>> {
    let mut v = Vec::new();
    leaves(&s.root, &mut v);
    v.into_iter().map(|l| l.1).collect()
}

#[test]
fn cameras() {
    let s = scene(&format!("{CAMERA}Group {{ numObjects 0 }}"));
    let want = Camera::Orthographic {
        center: Vec3::new(0.0, 0.0, 10.0).as_dvec3(),
        direction: -Vec3::Z,
        up: Vec3::Y,
        size: 5.0,
    };
    assert_eq!(s.camera, want);
    let s = scene(
        "PerspectiveCamera{angle 30 up 0 1 0 center 1 2 3 direction 0 0 -1}Group{numObjects 0}",
    );
    assert!(
        matches!(s.camera, Camera::Perspective { angle_deg, center, .. } if angle_deg == 30.0 && center == glam::DVec3::new(1.0, 2.0, 3.0))
    );
}

#[test]
fn lights_and_attenuation_default() {
    let s = scene(&format!(
        "{CAMERA}Lights {{ numLights 3\n DirectionalLight {{ direction 0 -1 0 color 1 1 1 }}\n\
         PointLight {{ position 1 2 3 color 0.5 0.5 0.5 }}\n\
         PointLight {{ position 0 0 0 color 1 0 0 attenuation 0 0.5 2 }} }}\nGroup {{ numObjects 0 }}"
    ));
    assert_eq!(s.lights.len(), 3);
    assert_eq!(
        s.lights[0],
        Light::Directional {
            direction: -Vec3::Y,
            color: Vec3::ONE
        }
    );
    assert!(matches!(s.lights[1], Light::Point { attenuation, .. } if attenuation == Vec3::X));
    assert!(
        matches!(s.lights[2], Light::Point { attenuation, .. } if attenuation == Vec3::new(0.0, 0.5, 2.0))
    );
    // With lights, the ambient light is what the file says (default 0).
    assert_eq!(s.background, Background::default());
}

#[test]
fn no_lights_forces_white_ambient() {
    let s = scene(&format!(
        "{CAMERA}Background {{ color 0 0 0 ambientLight 0.2 0.2 0.2 }} Group {{ numObjects 0 }}"
    ));
    assert_eq!(s.background.ambient, Vec3::ONE);
    assert_eq!(s.background.color, Vec3::ZERO);
    let s = scene(&format!(
        "{CAMERA}Lights {{ numLights 0 }} Group {{ numObjects 0 }}"
    ));
    assert_eq!(s.background.ambient, Vec3::ONE);
    assert_eq!(s.background.color, Vec3::splat(0.5));
}

#[test]
fn materials_defaults_and_fields() {
    let s = scene(&format!(
        "{CAMERA}Materials {{ numMaterials 3\n Material {{ diffuseColor 1 0 0 }}\n PhongMaterial {{ }}\n\
         PhongMaterial {{ indexOfRefraction 1.5 exponent 64 transparentColor .5 .5 .5 reflectiveColor 0.1 0.1 0.1 \
         specularColor 1 1 1 diffuseColor 0 0 1 }} }}\nGroup {{ numObjects 0 }}"
    ));
    assert_eq!(
        s.materials[0],
        Material::Phong(Phong {
            diffuse: Vec3::X,
            ..Phong::default()
        })
    );
    assert_eq!(s.materials[1], Material::Phong(Phong::default()));
    let want = Phong {
        diffuse: Vec3::Z,
        specular: Vec3::ONE,
        exponent: 64.0,
        reflective: Vec3::splat(0.1),
        transparent: Vec3::splat(0.5),
        ior: 1.5,
        glossiness: 0.0,
        emission: Vec3::ZERO,
    };
    assert_eq!(s.materials[2], Material::Phong(want));
}

/// `emittedColor`: a radiance on any material, blended by textures like
/// every other field, absent from the course's materials.
#[test]
fn emitted_color() {
    let s = scene(&format!(
        "{CAMERA}Materials {{ numMaterials 4\n PhongMaterial {{ diffuseColor 0 0 0 emittedColor 17 12 4 }}\n\
         Material {{ emittedColor 0.5 0 10000 diffuseColor .2 .2 .2 }}\n PhongMaterial {{ }}\n\
         Checkerboard {{ materialIndex 0 materialIndex 2 }} }}\nGroup {{ numObjects 0 }}"
    ));
    let Material::Phong(a) = &s.materials[0] else {
        panic!("{:?}", s.materials[0])
    };
    assert_eq!(a.emission, Vec3::new(17.0, 12.0, 4.0));
    assert_eq!(a.diffuse, Vec3::ZERO);
    let Material::Phong(b) = &s.materials[1] else {
        panic!("{:?}", s.materials[1])
    };
    assert_eq!(b.emission, Vec3::new(0.5, 0.0, 10000.0));
    assert_eq!(s.materials[2], Material::Phong(Phong::default()));
    assert_eq!(Phong::default().emission, Vec3::ZERO);
    let half = a.lerp(&Phong::default(), 0.5);
    assert_eq!(half.emission, Vec3::new(8.5, 6.0, 2.0));
    // (input, the token the error points at, the message)
    for (bad, at, want) in [
        (
            "emittedColor -1 0 0",
            "-1",
            "expected a colour component from 0 to 10000, found '-1'",
        ),
        (
            "emittedColor 1 1 10001",
            "10001",
            "from 0 to 10000, found '10001'",
        ),
        ("emittedColor 1 1 }", "}", "expected a number, found '}'"),
        (
            "emittedColor 1 1 1 emittedColor 2 2 2",
            "emittedColor 2",
            "emittedColor",
        ),
    ] {
        let head = "Materials { numMaterials 1 PhongMaterial { ";
        let e = error(&format!(
            "{CAMERA}{head}{bad} }} }}\nGroup {{ numObjects 0 }}"
        ));
        assert!(e.to_string().contains(want), "{bad}: {e}");
        let col = head.len() + bad.find(at).unwrap() + 1;
        assert_eq!((e.line, e.col), (2, col), "{bad}: {e}");
    }
}

#[test]
fn textures() {
    let s = scene(&format!(
        "{CAMERA}Materials {{ numMaterials 6 Material {{}} Material {{}}\n\
         Checkerboard {{ Transform {{ UniformScale 2 }} materialIndex 0 materialIndex 1 }}\n\
         Noise {{ materialIndex 1 materialIndex 0 octaves 3 }}\n\
         Marble {{ materialIndex 0 materialIndex 1 octaves 4 frequency 2 amplitude 0.5 }}\n\
         Wood {{ materialIndex 2 materialIndex 3 amplitude 1 frequency 3 octaves 2 }} }}\nGroup {{ numObjects 0 }}"
    ));
    let tex = |i: usize| match &s.materials[i] {
        Material::Texture {
            kind,
            transform,
            a,
            b,
        } => (kind.clone(), *transform, *a, *b),
        m => panic!("not a texture: {m:?}"),
    };
    assert_eq!(
        tex(2),
        (
            TextureKind::Checkerboard,
            Mat4::from_scale(Vec3::splat(2.0)),
            0,
            1
        )
    );
    assert_eq!(
        tex(3),
        (TextureKind::Noise { octaves: 3 }, Mat4::IDENTITY, 1, 0)
    );
    assert_eq!(
        tex(4).0,
        TextureKind::Marble {
            octaves: 4,
            frequency: 2.0,
            amplitude: 0.5
        }
    );
    assert_eq!(
        tex(5).0,
        TextureKind::Wood {
            octaves: 2,
            frequency: 3.0,
            amplitude: 1.0
        }
    );
    assert_eq!((tex(5).2, tex(5).3), (2, 3));
}

#[test]
fn texture_must_refer_to_earlier_materials() {
    let e = error(&format!(
        "{CAMERA}Materials {{ numMaterials 2\nCheckerboard {{ materialIndex 0 materialIndex 1 }}\nMaterial {{}} }}"
    ));
    assert_eq!((e.line, e.col), (3, 30));
    assert!(e.expected.contains("earlier"), "{e}");
}

/// Positions keep every digit the file gives (read as f64): at 10⁵ an f32
/// would read 0.3 as 0.3046875; directions and radii stay f32.
#[test]
fn positions_are_read_in_double_precision() {
    let s = scene(&format!(
        "{CAMERA}Lights {{ numLights 4\n\
         PointLight {{ position 100000.3 -2.1 7 color 1 1 1 }}\n\
         AreaLight {{ quad {{ corner 100000.3 1 2 edge1 1 0 0 edge2 0 0 1 }} color 1 1 1 power 1 }}\n\
         AreaLight {{ disk {{ center 1 100000.3 2 normal 0 1 0 radius 0.5 }} color 1 1 1 power 1 }}\n\
         AreaLight {{ sphere {{ center 1 2 100000.3 radius 0.1 }} color 1 1 1 power 1 }} }}\n\
         Group {{ numObjects 3\n Sphere {{ center 100000.3 0 0 radius 0.1 }}\n\
         Plane {{ normal 0 1 0 offset 100000.3 }}\n\
         Triangle {{ vertex0 100000.3 0 0 vertex1 0 100000.3 0 vertex2 0 0 100000.3 }} }}"
    ));
    let x = 100000.3;
    assert_ne!(x as f32 as f64, x);
    assert!(
        matches!(s.lights[0], Light::Point { position, .. } if position == DVec3::new(x, -2.1, 7.0))
    );
    let centres: Vec<DVec3> = (s.lights[1..].iter())
        .map(|l| match l {
            Light::Area { shape, .. } => match *shape {
                AreaShape::Quad { corner, .. } => corner,
                AreaShape::Disk { center, .. } | AreaShape::Sphere { center, .. } => center,
            },
            l => panic!("{l:?}"),
        })
        .collect();
    assert_eq!(
        centres,
        [
            DVec3::new(x, 1.0, 2.0),
            DVec3::new(1.0, x, 2.0),
            DVec3::new(1.0, 2.0, x)
        ]
    );
    let mut l = Vec::new();
    leaves(&s.root, &mut l);
    assert_eq!(
        l[0].0,
        ShapeDesc::Sphere {
            center: DVec3::new(x, 0.0, 0.0),
            radius: 0.1
        }
    );
    assert_eq!(
        l[1].0,
        ShapeDesc::Plane {
            normal: Vec3::Y,
            offset: x
        }
    );
    assert_eq!(
        l[2].0,
        ShapeDesc::Triangle([DVec3::X * x, DVec3::Y * x, DVec3::Z * x])
    );
}

#[test]
fn objects() {
    let s = scene(&format!(
        "{CAMERA}Materials {{ numMaterials 1 Material {{}} }}\nGroup {{ numObjects 4 MaterialIndex 0\n\
         Sphere {{ radius 2 center 1 2 3 }}\n Plane {{ normal 0 1 0 offset -1 }}\n\
         Triangle {{ vertex0 0 0 0 vertex1 1 0 0 vertex2 0 1 0 }}\n\
         Transform {{ Translate 1 0 0 Group {{ numObjects 0 }} }} }}"
    ));
    let mut l = Vec::new();
    leaves(&s.root, &mut l);
    assert_eq!(
        l[0].0,
        ShapeDesc::Sphere {
            center: Vec3::new(1.0, 2.0, 3.0).as_dvec3(),
            radius: 2.0
        }
    );
    assert_eq!(
        l[1].0,
        ShapeDesc::Plane {
            normal: Vec3::Y,
            offset: -1.0
        }
    );
    assert_eq!(
        l[2].0,
        ShapeDesc::Triangle([DVec3::ZERO, DVec3::X, DVec3::Y])
    );
    let Node::Group(top) = &s.root else { panic!() };
    assert!(
        matches!(&top[3], Node::Transform { matrix, child } if *matrix == Mat4::from_translation(Vec3::X).as_dmat4() && **child == Node::Group(vec![]))
    );
}

#[test]
fn degenerate_triangles_are_allowed() {
    scene(&format!(
        "{CAMERA}Group {{ numObjects 1 Triangle {{ vertex0 1 1 1 vertex1 1 1 1 vertex2 1 1 1 }} }}"
    ));
}

#[test]
fn material_index_is_sticky_and_scoped() {
    let s = scene(&format!(
        "{CAMERA}Materials {{ numMaterials 3 Material {{}} Material {{}} Material {{}} }}\n\
         Group {{ numObjects 5\n\
           Sphere {{ center 0 0 0 radius 1 }}\n\
           MaterialIndex 1\n\
           Sphere {{ center 0 0 0 radius 1 }}\n\
           Group {{ numObjects 2 Sphere {{ center 0 0 0 radius 1 }} MaterialIndex 2 Sphere {{ center 0 0 0 radius 1 }} }}\n\
           Transform {{ Scale 1 2 1 Sphere {{ center 0 0 0 radius 1 }} }}\n\
           Sphere {{ center 0 0 0 radius 1 }} }}"
    ));
    assert_eq!(
        materials_of(&s),
        [None, Some(1), Some(1), Some(2), Some(1), Some(1)]
    );
}

#[test]
fn materials_may_follow_the_group() {
    let src = format!(
        "{CAMERA}Group {{ numObjects 1 MaterialIndex 1 Sphere {{ center 0 0 0 radius 1 }} }}\n"
    );
    let s = scene(&format!(
        "{src}Materials {{ numMaterials 2 Material {{}} Material {{}} }}"
    ));
    assert_eq!(materials_of(&s), [Some(1)]);
    let e = error(&format!(
        "{src}Materials {{ numMaterials 1 Material {{}} }}"
    ));
    assert_eq!((e.line, e.col), (2, 36));
    let e = error(&src);
    assert!(e.expected.contains("no materials"), "{e}");
}

#[test]
fn semantic_errors_point_at_the_value() {
    let cases = [
        (
            "OrthographicCamera { center 0 0 0 direction 0 0 0 up 0 1 0 size 1 }",
            1,
            45,
            "non-zero camera direction",
        ),
        (
            "OrthographicCamera { center 0 0 0 direction 0 0 1 up 0 0 -2 size 1 }",
            1,
            54,
            "not parallel",
        ),
        (
            "OrthographicCamera { center 0 0 0 direction 0 0 1 up 0 0 0 size 1 }",
            1,
            54,
            "non-zero up",
        ),
        (
            "OrthographicCamera { center 0 0 0 direction 0 0 1 up 0 1 0 size 0 }",
            1,
            65,
            "positive size",
        ),
        (
            "PerspectiveCamera { center 0 0 0 direction 0 0 1 up 0 1 0 angle 180 }",
            1,
            65,
            "between 0 and 180",
        ),
        ("Lights { numLights -1 }", 1, 20, "0 or more"),
        (
            "Group { numObjects 1 Sphere { center 0 0 0 radius -1 } }",
            1,
            51,
            "positive radius",
        ),
        (
            "Group { numObjects 1 Plane { normal 0 0 0 offset 1 } }",
            1,
            37,
            "non-zero plane normal",
        ),
        (
            "Group { numObjects 1 Transform { Scale 1 0 1 Sphere { center 0 0 0 radius 1 } } }",
            1,
            22,
            "invertible",
        ),
        (
            "Group { numObjects 1 Transform { Rotate 0 0 0 5 Sphere { center 0 0 0 radius 1 } } }",
            1,
            41,
            "axis",
        ),
        (
            "Materials { numMaterials 1 Material { indexOfRefraction 0 } }",
            1,
            57,
            "index of refraction",
        ),
    ];
    for (src, line, col, msg) in cases {
        let e = error(src);
        assert_eq!((e.line, e.col), (line, col), "{src}: {e}");
        assert!(e.to_string().contains(msg), "{src}: {e}");
    }
}

#[test]
fn structure_errors() {
    let e = error("Group { numObjects 0 }");
    assert!(e.expected.contains("a camera"), "{e}");
    let e = error(CAMERA);
    assert!(e.expected.contains("Group"), "{e}");
    let e = error(&format!("{CAMERA}{CAMERA}"));
    assert_eq!((e.line, e.col), (2, 1));
    let e = error(&format!(
        "{CAMERA}Group {{ numObjects 0 }} Group {{ numObjects 0 }}"
    ));
    assert_eq!(e.found, "a second 'Group'");
    let e = error(&format!(
        "{CAMERA}Group {{ numObjects 1 Sphere {{ center 0 0 0 radius 1 radius 2 }} }}"
    ));
    assert_eq!(e.found, "a 2nd 'radius'");
    let e = error(&format!(
        "{CAMERA}Group {{ numObjects 1 Sphere {{ center 0 0 0 }} }}"
    ));
    assert_eq!(
        e.to_string(),
        "t.txt:2:44: expected 'radius' in Sphere, found '}'"
    );
}

#[test]
fn count_mismatch_messages() {
    let e = error(&format!(
        "{CAMERA}Group {{ numObjects 2 Plane {{ normal 0 1 0 offset 0 }} }}"
    ));
    assert_eq!(
        e.to_string(),
        "t.txt:2:54: expected 2 objects (numObjects 2), found '}' after 1 object"
    );
    let s = "Plane { normal 0 1 0 offset 0 }";
    let e = error(&format!("{CAMERA}Group {{ numObjects 1 {s} {s} }}"));
    assert_eq!(e.expected, "1 object (numObjects 1)");
    assert_eq!(e.found, "a 2nd 'Plane'");
}

#[test]
fn deep_nesting_is_an_error_not_a_crash() {
    let depth = 100_000;
    let src = format!(
        "{CAMERA}{}{}",
        "Group { numObjects 1 ".repeat(depth),
        "}".repeat(depth)
    );
    let e = error(&src);
    assert!(e.expected.contains("nested"), "{e}");
}

#[test]
fn truncation_anywhere_is_an_error_never_a_panic() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let src = std::fs::read_to_string(dir.join("whitted.txt")).expect("scenes/whitted.txt");
    let full = parse(&src, &dir.join("x.txt"));
    assert!(full.is_ok());
    for (i, _) in src.char_indices() {
        let cut = &src[..i];
        if cut.trim_end().ends_with('}') && cut.matches('{').count() == cut.matches('}').count() {
            continue; // a prefix ending after a complete block may be valid or not
        }
        assert!(
            parse(cut, Path::new("x.txt")).is_err(),
            "prefix of {i} bytes parsed"
        );
    }
}

/// Triangle counts of the meshes the course's scenes name.
fn triangles_of(s: &Scene) -> usize {
    s.summary().triangles
}

#[test]
fn every_shared_scene_parses() {
    let Some(dir) = crate::testdata::scenes("every_shared_scene_parses") else {
        return;
    };
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .expect("course scenes folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "txt") && !p.ends_with("NOTES.md"))
        .collect();
    names.sort();
    assert!(names.len() >= 96, "only {} scenes", names.len());
    for path in &names {
        let s = crate::format::load_scene(path).unwrap_or_else(|e| panic!("{}", e.render()));
        let sum = s.summary();
        assert!(
            sum.spheres + sum.planes + sum.triangles > 0,
            "{} is empty",
            path.display()
        );
        // Every object's material exists.
        for m in materials_of(&s).into_iter().flatten() {
            assert!(m < s.materials.len(), "{}", path.display());
        }
    }
    let load = |name: &str| crate::format::load_scene(&dir.join(name)).unwrap();
    assert_eq!(triangles_of(&load("scene2_09_bunny_200.txt")), 200);
    assert_eq!(triangles_of(&load("scene6_07_bunny_mesh_40k.txt")), 40_000);
    let s = load("scene1_01.txt");
    assert_eq!(
        (
            s.summary().spheres,
            s.summary().groups,
            s.background.ambient
        ),
        (1, 1, Vec3::ONE)
    );
    let s = load("scene2_15_crazy_transforms.txt");
    assert_eq!(
        (
            s.summary().meshes,
            s.summary().transforms,
            s.summary().triangles
        ),
        (2, 5, 24)
    );
    let s = load("scene6_15_marble_cubes.txt");
    assert_eq!(s.materials.len(), 12);
    assert!(matches!(
        s.materials[8],
        Material::Texture {
            kind: TextureKind::Marble { octaves: 0, .. },
            a: 6,
            b: 7,
            ..
        }
    ));
}

#[test]
fn meshes_used_twice_are_loaded_once() {
    let Some(dir) = crate::testdata::scenes("meshes_used_twice_are_loaded_once") else {
        return;
    };
    let s = crate::format::load_scene(&dir.join("scene6_15_marble_cubes.txt")).unwrap();
    let mut l = Vec::new();
    leaves(&s.root, &mut l);
    let meshes: Vec<_> = l
        .iter()
        .filter_map(|(sh, _)| match sh {
            ShapeDesc::Mesh(m) => Some(m.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(meshes.len(), 4);
    assert!(meshes.iter().all(|m| std::sync::Arc::ptr_eq(m, &meshes[0])));
}

#[test]
fn distribution_blocks() {
    let s = scene(
        "PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30\n\
         aperture 0.2 focusDistance 8 shutter 0 0.5 }\n\
         Lights { numLights 3\n\
           AreaLight { quad { corner 0 4 0 edge1 1 0 0 edge2 0 0 1 } color 1 1 1 power 50 }\n\
           AreaLight { disk { center 0 4 0 normal 0 -1 0 radius 0.5 } color 1 0 0 power 5 }\n\
           AreaLight { power 2 sphere { radius 0.25 center 1 2 3 } color 0 1 0 } }\n\
         Samples { shadow 16 glossy 8 time 4 lens 2 }\n\
         AmbientOcclusion { samples 32 distance 2.5 }\n\
         Materials { numMaterials 1 PhongMaterial { reflectiveColor 1 1 1 glossiness 0.25 } }\n\
         Group { numObjects 1 KeyframedTransform { numKeyframes 2\n\
           Keyframe { time 0 }\n\
           Keyframe { time 1 translate 1 0 0 rotate 0 1 0 90 scale 2 2 2 }\n\
           Sphere { center 0 0 0 radius 1 } } }",
    );
    let e = &s.effects;
    assert_eq!(e.lens.aperture, 0.2);
    assert_eq!(e.lens.focus_distance, 8.0);
    assert_eq!(e.lens.shutter, [0.0, 0.5]);
    assert_eq!(
        (
            e.samples.shadow,
            e.samples.glossy,
            e.samples.time,
            e.samples.lens,
            e.samples.ao
        ),
        (16, 8, 4, 2, 32)
    );
    assert_eq!(e.ambient_occlusion.map(|a| a.distance), Some(2.5));
    assert_eq!(s.lights.len(), 3);
    assert!(matches!(
        s.lights[2],
        Light::Area { shape: crate::scene::AreaShape::Sphere { radius, .. }, power, .. }
            if radius == 0.25 && power == 2.0
    ));
    let Material::Phong(m) = &s.materials[0] else {
        panic!("phong expected")
    };
    assert_eq!(m.glossiness, 0.25);
    let Node::Group(kids) = &s.root else {
        panic!("group expected")
    };
    let Node::Moving { motion, .. } = &kids[0] else {
        panic!("moving node expected, got {:?}", kids[0])
    };
    let p = motion.matrix(1.0).transform_point3(Vec3::X);
    assert!((p - Vec3::new(1.0, 0.0, -2.0)).length() < 1e-5, "{p}");
    // Without the new blocks nothing changes.
    let plain = scene(&format!("{CAMERA}Group {{ numObjects 0 }}"));
    assert_eq!(plain.effects, crate::scene::Effects::default());
}

/// Issue 15: `octaves 2000000000` hung a tiny render; now every count has a
/// range, checked at the number.
#[test]
fn octaves_beyond_the_cap_are_refused_at_the_number() {
    let src = |n: &str| {
        format!(
            "{CAMERA}Materials {{ numMaterials 3 Material {{}} Material {{}}\n\
             Noise {{ materialIndex 1 materialIndex 0 octaves {n} }} }}\nGroup {{ numObjects 0 }}"
        )
    };
    assert!(parse(&src("32"), Path::new("t.txt")).is_ok());
    for n in ["33", "2000000000", "99999999999999"] {
        let e = error(&src(n));
        assert_eq!((e.line, e.col), (3, 49), "{n}");
        assert_eq!(e.expected, "an octave count from 0 to 32");
    }
}

/// Issue 15: a UTF-8 byte-order mark made the first keyword unknown, with the
/// mark invisible in the message.
#[test]
fn a_byte_order_mark_is_accepted_and_elsewhere_shown_escaped() {
    let bytes = format!("\u{feff}{CAMERA}Group {{ numObjects 0 }}");
    let text = crate::format::diagnostic_decode_for_tests(bytes.as_bytes());
    assert!(parse(text, Path::new("t.txt")).is_ok());
    let e = error(&format!("{CAMERA}\u{200b}Group {{ numObjects 0 }}"));
    assert_eq!(e.found, "'\\u{200b}Group'");
    assert!(e.render().contains("2 | \\u{200b}Group"), "{}", e.render());
}
