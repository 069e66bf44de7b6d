//! No algorithm call touches the heap once the workspace exists (what a real-time loop needs).
//! A counting global allocator watches every allocation made while the algorithms run.

mod common;

use common::{load_model, Rng};
use embedyn::{aba, crba, forward_kinematics, mass_matrix_inverse, rnea, Workspace};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

// One test in this binary, so no other test thread allocates while we count.
#[test]
fn algorithm_calls_do_not_allocate() {
    for (path, floating) in [
        ("models/arm7.urdf", false),
        ("models/humanoid34.urdf", true),
        ("models/quadruped.urdf", false),
    ] {
        let model = load_model::<f64>(path, floating);
        let mut ws = Workspace::new(&model);
        ws.reserve_inverse(&model);
        let mut rng = Rng(1);
        let q = rng.configuration(&model);
        let v = rng.vec(model.nv(), -1.0, 1.0);
        let tau = rng.vec(model.nv(), -1.0, 1.0);
        let before = ALLOCATIONS.load(Ordering::SeqCst);
        for _ in 0..3 {
            forward_kinematics(&model, &mut ws, &q, &v).unwrap();
            let _ = aba(&model, &mut ws, &q, &v, &tau).unwrap();
            let _ = rnea(&model, &mut ws, &q, &v, &tau).unwrap();
            let _ = crba(&model, &mut ws, &q).unwrap();
            let _ = mass_matrix_inverse(&model, &mut ws, &q).unwrap();
        }
        let after = ALLOCATIONS.load(Ordering::SeqCst);
        assert_eq!(
            after - before,
            0,
            "{path}: {} allocations inside algorithm calls",
            after - before
        );
    }
}
