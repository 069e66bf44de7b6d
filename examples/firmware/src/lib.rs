//! The firmware route of embedyn: a `#![no_std]` static library (for a motor driver or a flight
//! controller) whose dynamics are generated at build time by `embedyn::robot!` and need only `core`.
//! Built with `panic = "abort"` by `.ci/run`; a C caller links `libembedyn_firmware_example.a`.

#![no_std]

/// The seven-joint arm of `models/arm7.urdf`, generated at build time.
pub mod arm7 {
    embedyn::robot!("../../models/arm7.urdf", only(aba), f32_only);
}

/// Forward dynamics for C callers: `qdd = aba(q, v, tau)` in `f32`, seven joints, arrays of 7.
///
/// # Safety
/// Each pointer must point to 7 readable (`qdd`: writable) `f32`s.
#[no_mangle]
pub unsafe extern "C" fn arm7_aba(q: *const f32, v: *const f32, tau: *const f32, qdd: *mut f32) {
    let q = &*(q as *const [f32; arm7::NQ]);
    let v = &*(v as *const [f32; arm7::NV]);
    let tau = &*(tau as *const [f32; arm7::NV]);
    let qdd = &mut *(qdd as *mut [f32; arm7::NV]);
    arm7::f32::aba(q, v, tau, qdd);
}

// A firmware image has one panic handler; a second one (std's) would be "duplicate lang item
// `panic_impl`", which is what this crate checks cannot happen. Generated code does not panic.
#[cfg(not(test))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {}
}
