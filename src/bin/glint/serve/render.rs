//! Progressive refinement on top of the library's render call: pass `k`
//! renders `n_k` samples per pixel with the sampler seeded `k`, and the
//! server adds `n_k` × the pass's image to a running sum. After passes of
//! 1, 1, 2, 4, … samples the image is the average of independently seeded
//! renders whose sample counts add up to the target; its expected value is
//! that of one render at the target count, and its noise is the same order
//! (each pass is stratified on its own, not jointly with the others, so a
//! Sobol render at N spp is a little less noisy than the sum of its passes).
//! A uniform sampler places the same points in every pass: it is rendered in
//! one pass at the target count.

use super::params::{IntegratorName, View};
use glint::integrator::{AmbientOcclusion, AoSettings, PathSettings, PathTracer, Whitted};
use glint::math::Vec3;
use glint::render::{render_image, CameraModel, Control, Rendered, Settings};
use glint::sampler::{Sampler, SamplerKind};
use glint::scene::Scene;
use glint::world::World;

/// The camera a view renders through: the page's camera when it moved it,
/// else the scene's (at the shutter's opening, as `glint raytree` takes it).
pub fn camera(world: &World, scene: &Scene, view: &View) -> CameraModel {
    match &view.camera {
        Some(c) => CameraModel::new(c).with_lens(scene.effects.lens),
        None => CameraModel::of_world(world, &scene.effects).at_time(scene.effects.lens.shutter[0]),
    }
}

/// The Whitted integrator of a view, with the scene's sample counts (as
/// `glint render` sets it up).
pub fn whitted(scene: &Scene, view: &View) -> Whitted {
    let s = scene.effects.samples;
    Whitted {
        bounces: view.bounces,
        weight_cutoff: view.weight,
        shadows: view.shadows,
        shade_back: view.shade_back,
        shadow_samples: s.shadow,
        glossy_samples: s.glossy,
        ambient_occlusion: scene.effects.ambient_occlusion.map(|a| AoSettings {
            samples: s.ao,
            distance: a.distance,
        }),
        ..Whitted::default()
    }
}

/// Samples per pixel of pass `k` when `done` have been added towards
/// `target`: 1, 1, 2, 4, … (doubling the total each pass), the rest at the
/// end; a uniform sampler takes everything in pass 0.
pub fn pass_spp(kind: SamplerKind, done: u32, target: u32) -> u32 {
    if matches!(kind, SamplerKind::Uniform(_)) {
        return target.saturating_sub(done);
    }
    done.max(1).min(target.saturating_sub(done))
}

/// Renders one pass of `spp` samples per pixel seeded `seed`, with the
/// per-pixel cost plane.
pub fn pass(
    world: &World,
    scene: &Scene,
    view: &View,
    spp: u32,
    seed: u64,
    control: Control,
) -> Rendered {
    let cam = camera(world, scene, view);
    let mut settings = Settings::one_ray(view.size, glint::render::PixelOffset::CENTER);
    settings.sampler = Sampler::new(view.sampler, spp, seed);
    settings.filter = view.filter;
    settings.pixel_cost = true;
    match view.integrator {
        IntegratorName::Whitted => {
            render_image(world, &cam, &whitted(scene, view), &settings, control)
        }
        IntegratorName::Ao => {
            let s = scene.effects.samples;
            let ao = AmbientOcclusion {
                settings: AoSettings {
                    samples: s.ao,
                    distance: scene
                        .effects
                        .ambient_occlusion
                        .map_or(f32::INFINITY, |a| a.distance),
                },
            };
            render_image(world, &cam, &ao, &settings, control)
        }
        IntegratorName::Path => {
            // As `glint render --integrator path --bounces N`.
            let pt = PathTracer::new(
                world,
                PathSettings {
                    max_bounces: view.bounces,
                    ..PathSettings::default()
                },
            );
            render_image(world, &cam, &pt, &settings, control)
        }
    }
}

/// `pixels` (top row first, linear, clamped to 8 bits as `glint render`
/// writes PNG) encoded as PNG.
pub fn png(w: u32, h: u32, pixels: &[Vec3]) -> Result<Vec<u8>, String> {
    use image::ImageEncoder;
    let bytes: Vec<u8> = pixels
        .iter()
        .flat_map(|p| p.to_array().map(glint::output::to_byte))
        .collect();
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new_with_quality(
        &mut out,
        image::codecs::png::CompressionType::Fast,
        image::codecs::png::FilterType::Sub,
    )
    .write_image(&bytes, w, h, image::ExtendedColorType::Rgb8)
    .map_err(|e| e.to_string())?;
    Ok(out)
}
