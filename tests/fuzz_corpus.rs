//! Replays the committed fuzz corpora (`fuzz/corpus/<target>/`) through the fuzz targets' own checks
//! (`fuzz/harness.rs`) on the stable toolchain, so that every input the fuzzer kept — and every crash it
//! found, once fixed — stays checked by `cargo test`. Running the fuzzer itself: fuzz/README.md.

#[path = "../fuzz/harness.rs"]
mod harness;

use std::path::{Path, PathBuf};

fn corpus(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("a directory entry").path())
        .collect();
    files.sort();
    files
}

/// Runs `check` on every file, on all cores, and fails naming every input that failed its check.
fn replay(target: &str, check: fn(&[u8])) {
    let files = corpus(target);
    assert!(!files.is_empty(), "the {target} corpus is empty");
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let failed = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| loop {
                let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(path) = files.get(k) else { break };
                let data = std::fs::read(path).expect("a readable corpus file");
                if std::panic::catch_unwind(|| check(&data)).is_err() {
                    failed.lock().unwrap().push(path.display().to_string());
                }
            });
        }
    });
    let failed = failed.into_inner().unwrap();
    assert!(
        failed.is_empty(),
        "{} of {} {target} inputs fail their check:\n{}",
        failed.len(),
        files.len(),
        failed.join("\n")
    );
}

#[test]
fn urdf_corpus_replays_clean() {
    replay("urdf", harness::urdf);
}

#[test]
fn eval_input_corpus_replays_clean() {
    replay("eval_input", harness::eval_input);
}
