//! Helpers shared by the integration tests: paths to the repo's models, deterministic random states.
#![allow(dead_code)]

use embedyn::{load, Model, ModelOptions, Real};
use std::path::PathBuf;

pub fn repo_path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

pub fn load_model<T: Real>(rel: &str, floating: bool) -> Model<T> {
    let loaded = load(&repo_path(rel)).unwrap_or_else(|e| panic!("{e}"));
    loaded
        .model::<T>(&ModelOptions { floating, ..Default::default() })
        .unwrap_or_else(|e| panic!("{e}"))
}

/// SplitMix64: a tiny deterministic generator, so failures reproduce from the seed alone.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
    pub fn vec(&mut self, n: usize, lo: f64, hi: f64) -> Vec<f64> {
        (0..n).map(|_| self.uniform(lo, hi)).collect()
    }
    /// A random configuration: angles in [−π, π], displacements in [−0.5, 0.5], a random unit quaternion.
    pub fn configuration<T: Real>(&mut self, model: &Model<T>) -> Vec<f64> {
        let mut q = vec![0.0; model.nq()];
        for j in &model.joints {
            let i = j.q_index;
            match j.joint_type {
                embedyn::JointType::Floating => {
                    for k in 0..3 {
                        q[i + k] = self.uniform(-1.0, 1.0);
                    }
                    let quat = self.vec(4, -1.0, 1.0);
                    let n = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
                    for k in 0..4 {
                        q[i + 3 + k] = quat[k] / n;
                    }
                }
                embedyn::JointType::Prismatic => q[i] = self.uniform(-0.5, 0.5),
                _ => q[i] = self.uniform(-std::f64::consts::PI, std::f64::consts::PI),
            }
        }
        q
    }
}

pub fn cast<T: Real>(x: &[f64]) -> Vec<T> {
    x.iter().map(|&v| T::from_f64(v)).collect()
}

pub fn to_f64<T: Real>(x: &[T]) -> Vec<f64> {
    x.iter().map(|v| v.to_f64()).collect()
}
