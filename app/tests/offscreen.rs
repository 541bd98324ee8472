//! Off-screen renders: on eframe's kind of render state (egui_kittest builds
//! one as eframe does) and on a headless device they go through the same
//! pipelines, so they agree; coverage is where the model is.

use egui_wgpu::RendererOptions;
use lodstudio::render::{Camera, Offscreen, Scene};
use lodstudio_core::Progress;
use lodstudio_core::distance::visual;

fn sphere() -> Scene {
    Scene::from_model(&lodstudio_core::builtins::build("sphere", &Progress::new()).unwrap())
}

/// The studio renders on a worker thread.
const _: fn(Offscreen) -> Box<dyn Send> = |o| Box::new(o);

#[test]
fn a_render_state_and_a_headless_device_render_alike() {
    let scene = sphere();
    let cameras = Camera::views_around(scene.sphere(), 2, 1.0);
    let rs = egui_kittest::wgpu::create_render_state(
        egui_kittest::wgpu::default_wgpu_setup(),
        RendererOptions::default(),
    );
    let studio = Offscreen::new(&rs)
        .render(&scene, &cameras, scene.sphere(), [96, 64])
        .unwrap();
    let headless = Offscreen::headless()
        .unwrap()
        .render(&scene, &cameras, scene.sphere(), [96, 64])
        .unwrap();
    assert_eq!(studio.len(), 2);
    for (a, b) in studio.iter().zip(&headless) {
        assert_eq!((a.image.width, a.image.height), (96, 64));
        assert_eq!(a.image.rgba.len(), 96 * 64);
        let d = visual::difference(a, b);
        assert!(d.silhouette < 0.01 && d.psnr > 40.0, "{d:?}");
        // A framed sphere (its bounding box's sphere fills the height) covers
        // the middle, not the corners, and its pixels are shaded, not background.
        let covered = a.coverage.iter().filter(|&&c| c).count() as f64 / a.coverage.len() as f64;
        assert!((0.08..0.5).contains(&covered), "{covered}");
        assert!(a.coverage[32 * 96 + 48] && !a.coverage[0] && !a.coverage[96 * 64 - 1]);
        assert_ne!(a.image.rgba[32 * 96 + 48], a.image.rgba[0]);
        assert!(a.image.rgba.iter().all(|p| p[3] == 255), "opaque");
    }
}

/// AMG splats (alpha-blended, Ψ-weighted) count as covering where their
/// domains' cores lock the depth (Ψ ≥ ½, front-facing), as the viewport
/// draws them: an impostor of the octahedron's points covers part of every
/// view.
#[test]
fn splat_impostors_cover_their_domains() {
    let points = lodstudio_core::builtins::octahedron_points(4000, 7);
    let ms =
        lodstudio_core::amg::decompose(&points, &Default::default(), &Progress::new()).unwrap();
    let texel = ms.default_texel();
    let mut h = lodstudio_core::amg::AmgHierarchy::new(ms, texel);
    use lodstudio_core::lod::Hierarchy as _;
    let d = h.diagonal();
    let view = lodstudio_core::view::View::orbit(glam::Vec3::ZERO, d, 0.0, 0.0);
    let set = h.select(&view, lodstudio_core::view::Tolerance::Relative(0.2));
    assert!(!set.splats.is_empty());
    let splats = Scene::from_draw_set(&set, &Default::default());
    let cameras = Camera::views_around(splats.sphere(), 4, 1.0);
    let renders = Offscreen::headless()
        .unwrap()
        .render(&splats, &cameras, splats.sphere(), [96, 96])
        .unwrap();
    for r in &renders {
        let covered = r.coverage.iter().filter(|&&c| c).count() as f64 / r.coverage.len() as f64;
        assert!(covered > 0.02, "{covered}");
    }
}
