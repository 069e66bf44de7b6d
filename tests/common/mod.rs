//! Helpers shared by the integration tests: paths to the repo's models, deterministic random states.
#![allow(dead_code)]

use embedyn::random::SplitMix64;
use embedyn::{load, Model, ModelOptions, Real};
use std::path::PathBuf;

/// What the output arrays hold before a generated function writes them: an entry it leaves unwritten
/// (a structural zero it fails to store) shows as an error of 1e9.
pub const UNWRITTEN: f64 = 1.0e9;

pub fn repo_path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// The repo's model file `rel` with each `(from, to)` replaced (every occurrence; each must occur), read
/// by the loader: the variations of a bundled model the tests need, without a file for each.
pub fn edited_model(
    rel: &str,
    edits: &[(&str, &str)],
) -> Result<embedyn::Loaded, embedyn::LoadError> {
    let path = repo_path(rel);
    let mut text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{rel}: {e}"));
    for (from, to) in edits {
        assert!(text.contains(from), "{rel} no longer contains {from}");
        text = text.replace(from, to);
    }
    embedyn::codegen::parse_urdf(&text, &path)
}

pub fn load_model<T: Real>(rel: &str, floating: bool) -> Model<T> {
    let loaded = load(&repo_path(rel)).unwrap_or_else(|e| panic!("{e}"));
    loaded
        .model::<T>(&ModelOptions {
            floating,
            ..Default::default()
        })
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The crate's generator with the tests' own draws (vectors, configurations) on top; the numbers come from
/// `embedyn::random::SplitMix64`, so failures reproduce from the seed alone.
pub struct Rng(SplitMix64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(SplitMix64::new(seed))
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0.next_u64()
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0.uniform(lo, hi)
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
    /// `n` random states `(q, v, u)` of fixed size for generated functions: configurations as
    /// [`Rng::configuration`], `v` and `u` uniform in [−1, 1) (the benchmarks' states).
    #[allow(dead_code, clippy::type_complexity)]
    pub fn states<T: Real, const NQ: usize, const NV: usize>(
        &mut self,
        model: &Model<T>,
        n: usize,
    ) -> (Vec<[f64; NQ]>, Vec<[f64; NV]>, Vec<[f64; NV]>) {
        let q = (0..n)
            .map(|_| self.configuration(model).try_into().unwrap())
            .collect();
        let v = (0..n)
            .map(|_| self.vec(NV, -1.0, 1.0).try_into().unwrap())
            .collect();
        let u = (0..n)
            .map(|_| self.vec(NV, -1.0, 1.0).try_into().unwrap())
            .collect();
        (q, v, u)
    }
}

pub fn cast<T: Real>(x: &[f64]) -> Vec<T> {
    x.iter().map(|&v| T::from_f64(v)).collect()
}

pub fn to_f64<T: Real>(x: &[T]) -> Vec<f64> {
    x.iter().map(|v| v.to_f64()).collect()
}

/// A random kinematic tree of `n` bodies: random branching (half the time a chain continues from the
/// last body), revolute or prismatic joints with axis-aligned or general axes, random placements and
/// physically valid random inertias. With `floating`, body 0 hangs on a floating joint.
pub fn random_tree(rng: &mut Rng, n: usize, floating: bool) -> Model<f64> {
    use embedyn::nalgebra::{Matrix3, Vector3};
    use embedyn::{JointType, SpatialInertia, Transform};
    let mut b = Model::<f64>::builder(format!("random{n}"));
    for i in 0..n {
        let parent = if i == 0 {
            None
        } else if rng.uniform(0.0, 1.0) < 0.5 {
            Some(i - 1)
        } else {
            Some((rng.next_u64() % i as u64) as usize)
        };
        let jtype = if i == 0 && floating {
            JointType::Floating
        } else if rng.uniform(0.0, 1.0) < 0.2 {
            JointType::Prismatic
        } else {
            JointType::Revolute
        };
        let axis = match rng.next_u64() % 5 {
            0 => Vector3::x(),
            1 => Vector3::y(),
            2 => Vector3::z(),
            3 => -Vector3::z(),
            _ => {
                let a = Vector3::new(
                    rng.uniform(-1.0, 1.0),
                    rng.uniform(-1.0, 1.0),
                    rng.uniform(-1.0, 1.0),
                );
                a / a.norm()
            }
        };
        let rpy = if rng.uniform(0.0, 1.0) < 0.3 {
            [0.0; 3]
        } else {
            [
                rng.uniform(-3.0, 3.0),
                rng.uniform(-1.5, 1.5),
                rng.uniform(-3.0, 3.0),
            ]
        };
        let placement = Transform::from_xyz_rpy(
            [
                rng.uniform(-0.4, 0.4),
                rng.uniform(-0.4, 0.4),
                rng.uniform(-0.4, 0.4),
            ],
            rpy,
        );
        let mass = rng.uniform(0.1, 5.0);
        let com = Vector3::new(
            rng.uniform(-0.2, 0.2),
            rng.uniform(-0.2, 0.2),
            rng.uniform(-0.2, 0.2),
        );
        // Principal moments from a random box: they satisfy the triangle inequality.
        let (x, y, z) = (
            rng.uniform(0.02, 0.4),
            rng.uniform(0.02, 0.4),
            rng.uniform(0.02, 0.4),
        );
        let d = Matrix3::from_diagonal(&Vector3::new(y * y + z * z, x * x + z * z, x * x + y * y))
            * (mass / 12.0);
        let r = Transform::<f64>::from_xyz_rpy(
            [0.0; 3],
            [
                rng.uniform(-3.0, 3.0),
                rng.uniform(-1.5, 1.5),
                rng.uniform(-3.0, 3.0),
            ],
        )
        .rotation;
        let inertia = SpatialInertia::from_com(mass, com, r * d * r.transpose());
        b.add_body(
            parent,
            format!("j{i}"),
            jtype,
            axis,
            placement,
            format!("b{i}"),
            inertia,
        )
        .unwrap();
    }
    b.build().unwrap()
}

/// The larger of two error measures, where a NaN counts as an infinite error. `f64::max` returns the
/// other operand when one is NaN, so `worst.max(|a − b|)` lets a result that failed (a NaN) pass a
/// tolerance check; every hand-written running maximum of an error goes through this instead.
pub fn worse(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::INFINITY
    } else {
        a.max(b)
    }
}

#[test]
fn a_nan_error_is_the_worst_error() {
    assert_eq!(worse(1e-3, f64::NAN), f64::INFINITY);
    assert_eq!(worse(f64::NAN, 0.0), f64::INFINITY);
    assert_eq!(
        [0.5, f64::NAN, 0.25].into_iter().fold(0.0, worse),
        f64::INFINITY
    );
    assert_eq!(worse(1e-3, 2e-3), 2e-3);
}

/// Spectral condition number of a symmetric positive-definite matrix.
pub fn condition_number(m: &embedyn::nalgebra::DMatrix<f64>) -> f64 {
    let e = m.clone().symmetric_eigen().eigenvalues;
    e.max() / e.min()
}

/// A chain of `n` revolute bodies, axes alternating z and y, 0.2 m links of 1 kg with realistic inertia.
pub fn chain(n: usize) -> Model<f64> {
    chain_with_masses(n, |_| 1.0)
}

/// [`chain`] with body `i` of `mass(i)` kg (its inertia scaled with it).
pub fn chain_with_masses(n: usize, mass: impl Fn(usize) -> f64) -> Model<f64> {
    use embedyn::nalgebra::{Matrix3, Vector3};
    use embedyn::{JointType, SpatialInertia, Transform};
    let mut b = Model::<f64>::builder(format!("chain{n}"));
    for i in 0..n {
        let axis = if i % 2 == 0 {
            Vector3::z()
        } else {
            Vector3::y()
        };
        let m = mass(i);
        let inertia = SpatialInertia::from_com(
            m,
            Vector3::new(0.0, 0.0, 0.1),
            Matrix3::from_diagonal(&Vector3::new(4e-3 * m, 4e-3 * m, 1e-3 * m)),
        );
        let placement = Transform::from_xyz_rpy([0.0, 0.0, 0.2], [0.0; 3]);
        b.add_body(
            i.checked_sub(1),
            format!("j{i}"),
            JointType::Revolute,
            axis,
            placement,
            format!("b{i}"),
            inertia,
        )
        .unwrap();
    }
    b.build().unwrap()
}

/// The toggle of models/loops/singular_four_bar.urdf: the parallelogram lying flat, crank and rocker at
/// +π/3, coupler at −π/3 (exact coordinates: Newton converges only linearly into a singular point, so
/// completion cannot place it there).
pub fn parallelogram_toggle(model: &Model<f64>) -> Vec<f64> {
    let toggle = std::f64::consts::FRAC_PI_3;
    let mut q = model.neutral_configuration();
    for (name, value) in [
        ("crank_joint", toggle),
        ("coupler_joint", -toggle),
        ("rocker_joint", toggle),
    ] {
        q[model.joints[model.joint_index(name).unwrap()].q_index] = value;
    }
    q
}
