//! # embedyn
//!
//! Exact, fast rigid-body dynamics for robots described in URDF and URDF+, including robots with local
//! closed loops (gears, rotors, four-bar linkages) through A. Jain's constraint embedding.
//!
//! This facade is the crate users depend on. It re-exports the interpreted solver (`embedyn-runtime`),
//! the model loader (`embedyn-codegen`) and, from the code-generation issue on, the `robot!` macro.
//!
//! ```
//! use embedyn::{aba, load, ModelOptions, Workspace};
//! # let path = concat!(env!("CARGO_MANIFEST_DIR"), "/models/arm7.urdf");
//! let robot = load(path.as_ref())?;
//! let model = robot.model::<f64>(&ModelOptions::default())?;
//! let mut ws = Workspace::new(&model);
//! let q = vec![0.1; model.nq()];
//! let v = vec![0.0; model.nv()];
//! let tau = vec![0.0; model.nv()];
//! let qdd = aba(&model, &mut ws, &q, &v, &tau)?;
//! assert_eq!(qdd.len(), 7);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]
#![no_std]

#[cfg(feature = "std")]
extern crate std;

// The README's examples are doctests of this crate, so that they can never rot.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;

#[doc = include_str!("../docs/generated-code.md")]
#[cfg(doctest)]
pub struct GeneratedCodeDoctests;

#[cfg(feature = "std")]
pub use embedyn_codegen as codegen;
#[cfg(feature = "std")]
pub use embedyn_codegen::{load, LoadError, Loaded, LockedJoint, ModelOptions, Rotors, Warning};
pub use embedyn_macros::robot;
#[cfg(feature = "std")]
pub mod parallel;
pub use embedyn_runtime::*;
