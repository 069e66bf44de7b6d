//! The speed-against-accuracy table and figure of BENCHMARKS.md ("Rotors: exact or reflected"):
//! `embedyn tradeoff` on GRBDA's robots with geared rotors, in one run.
//!
//! ```sh
//! cargo run --release -p embedyn-cli --example tradeoff_table -- bench/results/tradeoff
//! ```
//! writes `tradeoff.md` (a Markdown table) and `tradeoff.svg` (error against time, log axes) into the
//! folder given, and prints the table.

use embedyn_cli::plot::{Marker, Plot, Series};
use embedyn_cli::tradeoff::tradeoff;
use embedyn_codegen::{load, ModelOptions, DEFAULT_COMPILE_MEMORY_MB};
use std::path::{Path, PathBuf};

/// The robots: GRBDA's files with geared rotors (tests/data/grbda), and the project's rotor chain.
const MODELS: [&str; 5] = [
    "tests/data/grbda/revolute_rotor_chain.urdf",
    "models/loops/rotor_chain_10.urdf",
    "tests/data/grbda/mit_humanoid_leg.urdf",
    "tests/data/grbda/mini_cheetah.urdf",
    "tests/data/grbda/mit_humanoid.urdf",
];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "bench/results/tradeoff".into()),
    );
    std::fs::create_dir_all(&out)?;
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut table = String::from(
        "| model | nv (exact / reflected) | scalar | rotors | generated `aba` ns | × exact f64 | relative error of q̈ (independent) |\n|---|---|---|---|---:|---:|---:|\n",
    );
    let mut plot = Plot::new(
        "generated aba on GRBDA's geared robots: speed against accuracy",
        "ns per call",
        "relative error of the independent accelerations",
    )
    .log_x()
    .log_y()
    .hline(1e-3, "three correct digits")
    .size(820.0, 500.0);
    for (k, model) in MODELS.iter().enumerate() {
        let loaded = load(&root.join(model))?;
        let exact = loaded.model::<f64>(&ModelOptions::default())?;
        let result = tradeoff(
            &loaded,
            &ModelOptions::default(),
            DEFAULT_COMPILE_MEMORY_MB,
            &mut |step| eprintln!("{model}: {step}"),
        )?;
        let base = result.variants[0].aba_ns;
        let name = Path::new(model)
            .file_stem()
            .unwrap()
            .to_string_lossy()
            .into_owned();
        for v in &result.variants {
            table.push_str(&format!(
                "| {name} | {} / {} | {} | {} | {:.0} | {:.2} | {:.1e} |\n",
                exact.nv(),
                exact.independent_nv(),
                v.scalar,
                v.rotors,
                v.aba_ns,
                v.aba_ns / base,
                v.rel_error
            ));
        }
        for (scalar, marker) in [("f64", Marker::Circle), ("f32", Marker::Square)] {
            let points: Vec<(f64, f64)> = result
                .variants
                .iter()
                .filter(|v| v.scalar == scalar)
                .map(|v| (v.aba_ns, v.rel_error))
                .collect();
            plot = plot.series(
                Series::new(format!("{name} {scalar} (exact → reflected)"), points)
                    .line(true)
                    .marker(marker)
                    .colour(k + 1),
            );
        }
    }
    std::fs::write(out.join("tradeoff.md"), &table)?;
    std::fs::write(out.join("tradeoff.svg"), plot.to_svg())?;
    println!("{table}");
    Ok(())
}
