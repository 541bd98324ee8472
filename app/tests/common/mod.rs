//! The studio under egui_kittest with a real wgpu renderer (llvmpipe or
//! lavapipe on machines without a GPU), shared by the GUI tests and the
//! studio benchmark (`benches/studio.rs` includes this file).

use std::io::Write as _;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use egui_kittest::Harness;
use egui_kittest::wgpu::{WgpuTestRenderer, create_render_state, default_wgpu_setup};
use lodstudio::studio::StudioApp;

const MAX_WAIT_FRAMES: usize = 6000;
const MAX_WAIT_TIME: Duration = Duration::from_secs(300);

/// A harness whose renderer shares its wgpu state with the studio's viewport,
/// so the paint callback finds its pipelines.
pub fn studio(initial: Option<PathBuf>) -> Harness<'static, StudioApp> {
    let render_state = create_render_state(
        default_wgpu_setup(),
        egui_wgpu::RendererOptions::PREDICTABLE,
    );
    let app = StudioApp::with_render_state(Some(&render_state), initial);
    Harness::builder()
        .with_size([1280.0, 800.0])
        // Real-time-like frames, so two clicks make a double-click.
        .with_step_dt(1.0 / 60.0)
        .with_max_steps(120)
        .renderer(WgpuTestRenderer::from_render_state(render_state))
        .build_ui_state(|ui, app: &mut StudioApp| app.show(ui), app)
}

/// Steps frames (about 50 a second) while `busy` holds, bounded, then settles.
pub fn wait_while(harness: &mut Harness<'_, StudioApp>, what: &str, busy: fn(&StudioApp) -> bool) {
    let start = Instant::now();
    for _ in 0..MAX_WAIT_FRAMES {
        harness.step();
        if !busy(harness.state()) {
            harness.run();
            return;
        }
        assert!(
            start.elapsed() < MAX_WAIT_TIME,
            "still {what} after {MAX_WAIT_TIME:?}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    panic!("still {what} after {MAX_WAIT_FRAMES} frames");
}

/// Writes `image` as a binary PPM (no image codec needed) for a human to look at.
pub fn save_ppm(width: u32, height: u32, rgba: &[u8], name: &str) -> PathBuf {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}.ppm"));
    let mut bytes = format!("P6\n{width} {height}\n255\n").into_bytes();
    for px in rgba.chunks_exact(4) {
        bytes.extend_from_slice(&px[..3]);
    }
    let mut file = std::fs::File::create(&path).expect("create snapshot file");
    file.write_all(&bytes).expect("write snapshot file");
    path
}
