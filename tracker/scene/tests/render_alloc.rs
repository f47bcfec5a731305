//! Steady-state rendering must not touch the heap (the tracker renders every tick).

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use scene::geometry::Roi;
use scene::render::{CpuRenderer, RenderTarget, Renderer, Scene, SceneObject};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Counts allocations made by the thread that enabled counting.
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);
thread_local! {
    static COUNTING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.try_with(|c| c.get()).unwrap_or(false) {
            ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        }
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn repeated_roi_renders_do_not_allocate() {
    let mut r = CpuRenderer::new();
    let sphere = r.add_mesh(Arc::new(common::sphere(0.05, 30, 60))).unwrap();
    let cube = r.add_mesh(Arc::new(common::cube(0.06))).unwrap();
    let cam = common::vga();
    let roi = Roi::new(200.0, 120.0, 240.0, 240.0, 160, 160).unwrap();
    let mut target = RenderTarget::new();
    let mut render = |angle: f64, target: &mut RenderTarget| {
        let objects = [
            SceneObject {
                mesh: sphere,
                pose: Isometry3::from_parts(
                    Translation3::new(0.0, 0.0, 0.5),
                    UnitQuaternion::from_euler_angles(angle, 0.0, 0.0),
                ),
                id: 1,
            },
            SceneObject {
                mesh: cube,
                pose: Isometry3::from_parts(
                    Translation3::new(0.03, 0.02, 0.45),
                    UnitQuaternion::from_euler_angles(0.0, angle, 0.3),
                ),
                id: 2,
            },
        ];
        r.render_roi(&Scene::objects(&objects), &cam, &roi, target)
            .unwrap();
    };
    render(0.0, &mut target); // warm-up: buffers grow here
    COUNTING.with(|c| c.set(true));
    for k in 1..20 {
        render(f64::from(k) * 0.1, &mut target);
    }
    COUNTING.with(|c| c.set(false));
    assert_eq!(ALLOCATIONS.load(Ordering::SeqCst), 0);
    assert!(target.mask().contains(&1) && target.mask().contains(&2));
}
