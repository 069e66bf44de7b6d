//! # embedyn-codegen
//!
//! Model loading (URDF; URDF+ loops and couplings arrive with constraint embedding), the one model IR
//! every output is made from, and the `embedyn` command line. Code generation proper (the library API
//! for `build.rs` and the `robot!` macro) builds on the same IR.
//!
//! ```no_run
//! use embedyn_codegen::{load, ModelOptions};
//! let robot = load("models/arm7.urdf".as_ref()).unwrap();
//! for w in &robot.warnings { eprintln!("{w}"); }
//! let model = robot.model::<f64>(&ModelOptions::default()).unwrap();
//! println!("{} has {} degrees of freedom", model.name, model.nv());
//! ```

#![warn(missing_docs)]

pub mod algorithm;
mod assemble;
pub mod bounded_read;
mod dispatch;
pub use dispatch::AvxTwins;
mod emit;
mod emit_large;
mod error;
mod generate;
pub mod ir;
pub mod names;
mod pairing;
pub mod scene;
mod shared_bodies;
mod size;
#[cfg(feature = "standalone")]
pub mod standalone;
pub mod trace;
mod urdf;
mod value_names;
mod xml_text;
mod zero_stores;

pub use algorithm::UnknownAlgorithm;
pub use assemble::{build_model, inertial_about_link, ModelOptions, ROOT_JOINT};
pub use bounded_read::ReadError;
/// Where frame functions express their Jacobian and bias (`reference = …`, `--reference`).
pub use embedyn_runtime::Reference;
pub use emit::EmitError;
pub use error::{
    is_hidden_format, shortened, AxisOf, ConstraintElement, DescriptorMismatch, LoadError,
    LoadErrorKind, Location, Printable, Shared, Warning, WarningKind, MAX_KEPT_ERRORS,
    MAX_LISTED_ERRORS, MAX_SHOWN_CHARS,
};
pub use generate::{
    format_tokens, frame_function_names, generate_file, generate_source, generate_tokens,
    generation_model, Algorithm, GenerateOptions, LinkOptions, UnparsableCode, GENERATOR_VERSION,
};
pub use scene::{geared_rotors, GearedRotor, LockedJoint, Rotors};
pub use size::{FunctionSize, TooLargeToCompile, DEFAULT_COMPILE_MEMORY_MB};
pub use urdf::{load_urdf, parse_urdf, Loaded};

use embedyn_runtime::{Model, Real};
use std::path::Path;

/// Loads a model file (URDF or URDF+).
pub fn load(path: &Path) -> Result<Loaded, LoadError> {
    load_urdf(path)
}

impl Loaded {
    /// The interpreted model in scalar `T`.
    pub fn model<T: Real>(&self, options: &ModelOptions) -> Result<Model<T>, LoadError> {
        build_model(&self.robot, options)
    }

    /// The model as read, changed by the scene options that act on the file (`--lock`, `--rotors`):
    /// locked joints and reflected rotors are fixed joints in it, reflected couplings are gone.
    pub fn scene(
        &self,
        options: &ModelOptions,
    ) -> Result<std::borrow::Cow<'_, ir::Robot>, LoadError> {
        scene::apply(&self.robot, options)
    }
}
