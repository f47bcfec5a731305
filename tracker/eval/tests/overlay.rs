//! Overlay images: the reconstructed intensity in gray with the outline at the estimate, and a clear error when the
//! surface keeps no intensity to draw.

#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../../scene/tests/common/mod.rs"]
mod common;

use drivers::event::CdEvent;
use eval::{OverlayRenderer, OverlayWriter};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use std::sync::Arc;
use tracker::recon::{EventSurface, IntensityFilterConfig};
use tracker::track::{PoseEstimate, TrackingState};

fn estimate() -> PoseEstimate {
    PoseEstimate {
        object: 0,
        t_us: 1_000,
        pose: Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.5), UnitQuaternion::identity()),
        quality: 1.0,
        state: TrackingState::Tracking,
    }
}

/// A bright 2x2 patch at (10..12, 20..22) and a dark one at (30..32, 40..42).
fn patches() -> Vec<CdEvent> {
    let mut events = Vec::new();
    for (x0, y0, polarity) in [(10u16, 20u16, true), (30, 40, false)] {
        for y in y0..y0 + 2 {
            for x in x0..x0 + 2 {
                events.push(CdEvent {
                    t_us: 1_000,
                    x,
                    y,
                    polarity,
                });
            }
        }
    }
    events
}

#[test]
fn overlay_draws_intensity_and_the_outline_in_the_tracking_colour() {
    let cam = common::vga();
    let mesh = Arc::new(common::cube(0.1));
    let mut renderer = OverlayRenderer::new(cam, &[mesh]).expect("renderer");
    let mut surface = EventSurface::new(cam.width, cam.height, IntensityFilterConfig::default());
    surface.integrate(&patches());
    let img = renderer
        .draw(&surface, 1_000, &[estimate()])
        .expect("overlay draws");
    let gray = |x, y| img.get_pixel(x, y).0;
    assert!(gray(10, 20)[0] > 150, "{:?}", gray(10, 20));
    assert!(gray(30, 40)[0] < 100, "{:?}", gray(30, 40));
    assert_eq!(gray(600, 20), [128, 128, 128]);
    // The cube's outline at 0.5 m (about 105 px wide, centred) is drawn in green.
    let green = img.pixels().filter(|p| p.0 == [40, 230, 60]).count();
    assert!(green > 200, "{green} outline pixels");
}

#[test]
fn overlay_writer_names_a_directory_it_cannot_create() {
    let cam = common::vga();
    let mesh = Arc::new(common::cube(0.1));
    let file = std::env::temp_dir().join(format!("overlay-file-{}", std::process::id()));
    std::fs::write(&file, b"not a directory").expect("temp file");
    let renderer = OverlayRenderer::new(cam, &[mesh]).expect("renderer");
    let Err(err) = OverlayWriter::new(&file.join("frames"), 1, renderer) else {
        panic!("a directory under a file cannot be created");
    };
    let _ = std::fs::remove_file(&file);
    let msg = err.to_string();
    assert!(msg.contains("overlay directory"), "{msg}");
    assert!(msg.contains(&file.display().to_string()), "{msg}");
}

#[test]
fn overlay_writer_refuses_a_surface_without_intensity() {
    let cam = common::vga();
    let mesh = Arc::new(common::cube(0.1));
    let dir = std::env::temp_dir().join(format!("overlay-test-{}", std::process::id()));
    let renderer = OverlayRenderer::new(cam, &[mesh]).expect("renderer");
    let mut writer = OverlayWriter::new(&dir, 1, renderer).expect("writer");
    let mut surface = EventSurface::latest_times_only(cam.width, cam.height);
    surface.integrate(&patches());
    let err = writer
        .tick(0, &surface, 1_000, &[estimate()])
        .expect_err("nothing to draw");
    assert!(err.contains("intensity.always"), "{err}");
    assert_eq!(writer.written(), 0);
    let mut full = EventSurface::new(cam.width, cam.height, IntensityFilterConfig::default());
    full.integrate(&patches());
    writer
        .tick(0, &full, 1_000, &[estimate()])
        .expect("draws with intensity");
    assert_eq!(writer.written(), 1);
    assert!(dir.join("overlay_000000.png").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}
