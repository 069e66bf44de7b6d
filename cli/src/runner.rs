//! The compiled form of `--engine generated` and `embedyn bench`: the model's standalone crate plus a
//! small binary that evaluates or times its functions, built once with cargo into a per-user cache.
//!
//! A cache entry is trusted only after a check before each use: its manifest (`entry.json`) names the
//! generator version, the SHA-256 of the source the entry was built from and that of the built binary;
//! an entry whose manifest is missing, unreadable, stale or does not match the binary on disk is rebuilt,
//! never used and never a permanent failure. Every file is written to a temporary name and renamed into
//! place, so concurrent runs never see half a file.

use super::CliError;
use embedyn_codegen::standalone::{
    crate_files, crate_name, Binary, Library, Manifest, ManifestError,
};
use embedyn_codegen::{format_tokens, GenerateOptions, UnparsableCode, GENERATOR_VERSION};
use embedyn_codegen::{Algorithm, Loaded};
use proc_macro2::TokenStream;
use quote::{format_ident, quote};
use sha2::{Digest, Sha256};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Why the generated code's runner cannot be built, found in the cache or run.
#[derive(Debug, thiserror::Error)]
pub enum RunnerError {
    /// No cache folder: neither `EMBEDYN_CACHE_DIR`, `XDG_CACHE_HOME` nor `HOME` is set.
    #[error("the generated engine needs a cache folder of your own to build in, and HOME is not set: set \
             EMBEDYN_CACHE_DIR (or XDG_CACHE_HOME) to a folder that only you can write")]
    NoCacheFolder,
    /// A path of the cache cannot be resolved or examined.
    #[error("{}: {error}", .path.display())]
    Path {
        /// The path.
        path: PathBuf,
        /// Why.
        #[source]
        error: std::io::Error,
    },
    /// A folder of the cache cannot be created.
    #[error("{}: cannot create the cache folder: {error}", .path.display())]
    CreateFolder {
        /// The folder.
        path: PathBuf,
        /// Why.
        #[source]
        error: std::io::Error,
    },
    /// The cache root is not a folder.
    #[error("{}: the cache folder is not a folder; {CACHE_ADVICE}", .path.display())]
    NotAFolder {
        /// The cache root.
        path: PathBuf,
    },
    /// The cache root belongs to another user.
    #[error("{}: the cache folder belongs to another user (uid {uid}); {CACHE_ADVICE}", .path.display())]
    OtherOwner {
        /// The cache root.
        path: PathBuf,
        /// Its owner.
        uid: u32,
    },
    /// Other users can write to the cache root.
    #[error("{}: the cache folder is writable by other users (mode {mode:o}); `chmod 700` it or {CACHE_ADVICE}", .path.display())]
    WritableByOthers {
        /// The cache root.
        path: PathBuf,
        /// Its permission bits.
        mode: u32,
    },
    /// A folder above the cache root lets another user replace it.
    #[error("{}: a folder above the cache ({}, owner uid {uid}, mode {mode:o}) lets another user replace the cache folder; {CACHE_ADVICE}", .path.display(), .folder.display())]
    UnsafeAncestor {
        /// The cache root.
        path: PathBuf,
        /// The folder above it.
        folder: PathBuf,
        /// That folder's owner.
        uid: u32,
        /// Its permission bits.
        mode: u32,
    },
    /// A file of the cache cannot be written.
    #[error("{}: cannot write: {error}", .path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        error: std::io::Error,
    },
    /// The runner's source cannot be generated.
    #[error("{0}")]
    Source(#[from] RunnerSourceError),
    /// The runner's `Cargo.toml` cannot be written as TOML.
    #[error("{0}")]
    Manifest(#[from] ManifestError),
    /// Cargo cannot be started.
    #[error("cannot run cargo ({}): {error}", .cargo.to_string_lossy())]
    CannotRunCargo {
        /// The cargo program (`$CARGO`, else `cargo`).
        cargo: std::ffi::OsString,
        /// Why.
        #[source]
        error: std::io::Error,
    },
    /// Cargo could not compile the runner.
    #[error("compiling the generated code failed:\n{stderr}")]
    CompileFailed {
        /// What cargo printed on stderr.
        stderr: String,
    },
    /// The runner cargo built cannot be read.
    #[error("{}: the built runner cannot be read: {error}", .path.display())]
    BuiltUnreadable {
        /// The binary.
        path: PathBuf,
        /// Why.
        #[source]
        error: std::io::Error,
    },
    /// The cache entry's manifest cannot be written as JSON.
    #[error("cannot write the cache manifest: {0}")]
    EntryManifest(#[source] serde_json::Error),
    /// The cache entry changed between writing and checking it.
    #[error("{}: the cache entry changed while it was being written (another embedyn run?); try again", .path.display())]
    EntryChanged {
        /// The entry.
        path: PathBuf,
    },
    /// The runner cannot be started.
    #[error("cannot run {}: {error}", .binary.display())]
    CannotRun {
        /// The runner.
        binary: PathBuf,
        /// Why.
        #[source]
        error: std::io::Error,
    },
    /// Waiting for the runner failed.
    #[error("the generated code's runner: {0}")]
    Wait(#[source] std::io::Error),
    /// The runner exited with an error.
    #[error("the generated code's runner failed ({status}): {}", .stderr.trim())]
    Failed {
        /// Its exit status.
        status: std::process::ExitStatus,
        /// What it printed on stderr.
        stderr: String,
    },
    /// The runner stopped before reading all its input.
    #[error("the generated code's runner did not read its input: {0}")]
    InputNotRead(#[source] std::io::Error),
    /// The thread feeding the runner's input failed.
    #[error("the generated code's runner input could not be written")]
    InputNotWritten,
    /// The runner's output is not what was asked for.
    #[error("the generated code's runner {0}")]
    Output(#[from] RunnerOutputProblem),
}

/// What to do about a cache folder that is not private.
const CACHE_ADVICE: &str = "set EMBEDYN_CACHE_DIR to a folder of your own";

/// How the runner's output differs from what was asked for.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RunnerOutputProblem {
    /// Another count of rows.
    #[error("printed {printed} rows for {expected} expected")]
    RowCount {
        /// The rows printed.
        printed: usize,
        /// The rows expected.
        expected: usize,
    },
    /// A word that is not a number.
    #[error("printed {text:?} in row {row}, not a number")]
    NotANumber {
        /// The word.
        text: String,
        /// The row, counted from 0.
        row: usize,
    },
    /// A row of another length.
    #[error("printed {printed} numbers in row {row}, expected {expected}")]
    RowLength {
        /// The numbers printed.
        printed: usize,
        /// The row, counted from 0.
        row: usize,
        /// The numbers expected.
        expected: usize,
    },
    /// A time that is not a positive number.
    #[error("reported a time of {ns} ns")]
    BadTime {
        /// The time reported.
        ns: f64,
    },
}

/// Why the runner's `main.rs` cannot be generated.
#[derive(Debug, thiserror::Error)]
pub enum RunnerSourceError {
    /// The model's crate name is not a Rust identifier.
    #[error("`{krate}` is not an identifier: {error}")]
    NotAnIdentifier {
        /// The crate name.
        krate: String,
        /// The parser's error.
        #[source]
        error: syn::Error,
    },
    /// The timing loop's source does not lex (a bug).
    #[error("internal error: the timing loop does not parse: {0}")]
    TimingLoop(#[source] syn::Error),
    /// The generated `main.rs` does not parse (a bug).
    #[error("{0}")]
    Unparsable(#[from] UnparsableCode),
}

/// The cache folder: `$EMBEDYN_CACHE_DIR`, else `$XDG_CACHE_HOME/embedyn`, else `$HOME/.cache/embedyn`.
/// Never a shared folder such as the temporary directory: other users could plant a binary there.
pub fn cache_dir() -> Result<PathBuf, CliError> {
    let var = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
    if let Some(d) = var("EMBEDYN_CACHE_DIR") {
        return Ok(PathBuf::from(d));
    }
    // The XDG base directory specification ignores a relative path.
    if let Some(d) = var("XDG_CACHE_HOME").filter(|d| Path::new(d).is_absolute()) {
        return Ok(PathBuf::from(d).join("embedyn"));
    }
    match var("HOME") {
        Some(home) => Ok(PathBuf::from(home).join(".cache").join("embedyn")),
        None => Err(RunnerError::NoCacheFolder.into()),
    }
}

/// The cache folder as an absolute path (cargo runs in another working folder).
fn absolute_cache_dir() -> Result<PathBuf, CliError> {
    let dir = cache_dir()?;
    std::path::absolute(&dir).map_err(|error| RunnerError::Path { path: dir, error }.into())
}

/// Creates `dir` and any missing parents with mode 0700 (Unix).
fn create_private_dir(dir: &Path) -> Result<(), CliError> {
    let mut builder = std::fs::DirBuilder::new();
    builder.recursive(true);
    #[cfg(unix)]
    std::os::unix::fs::DirBuilderExt::mode(&mut builder, 0o700);
    builder.create(dir).map_err(|error| {
        RunnerError::CreateFolder {
            path: dir.to_path_buf(),
            error,
        }
        .into()
    })
}

/// The cache root, created if needed, resolved to its canonical path and checked: a binary found there is
/// executed, so no other user may be able to write to it or to replace it, or any folder above it, while
/// embedyn works. Checking the path as given and working through it later would not do: a symlink, or a
/// folder above that someone else can rename, could point elsewhere between the check and the use. So the
/// path is resolved once, every folder from `/` down is checked, and only the resolved path is used.
fn cache_root(folder: Option<&Path>) -> Result<PathBuf, CliError> {
    let given = match folder {
        Some(folder) => std::path::absolute(folder).map_err(|error| RunnerError::Path {
            path: folder.to_path_buf(),
            error,
        })?,
        None => absolute_cache_dir()?,
    };
    create_private_dir(&given)?;
    let root = std::fs::canonicalize(&given).map_err(|error| RunnerError::Path {
        path: given.clone(),
        error,
    })?;
    #[cfg(unix)]
    check_private_chain(&root)?;
    Ok(root)
}

/// Checks that `root` (a canonical path) is a folder of this user that no one else can write, and that no
/// folder above it lets another user replace it: each is owned by this user or root and writable by no
/// one else, unless it is sticky (as `/tmp`), where others cannot rename or delete what they do not own.
#[cfg(unix)]
fn check_private_chain(root: &Path) -> Result<(), CliError> {
    use std::os::unix::fs::MetadataExt;
    // SAFETY: geteuid has no preconditions and cannot fail.
    let me = unsafe { libc::geteuid() };
    let meta_of = |p: &Path| {
        std::fs::symlink_metadata(p).map_err(|error| RunnerError::Path {
            path: p.to_path_buf(),
            error,
        })
    };
    let path = root.to_path_buf();
    let meta = meta_of(root)?;
    if !meta.is_dir() {
        return Err(RunnerError::NotAFolder { path }.into());
    }
    if meta.uid() != me {
        return Err(RunnerError::OtherOwner {
            path,
            uid: meta.uid(),
        }
        .into());
    }
    if meta.mode() & 0o022 != 0 {
        return Err(RunnerError::WritableByOthers {
            path,
            mode: meta.mode() & 0o7777,
        }
        .into());
    }
    let mut child_owner = meta.uid();
    for folder in root.ancestors().skip(1) {
        let meta = meta_of(folder)?;
        let owner_trusted = meta.uid() == me || meta.uid() == 0;
        let others_write = meta.mode() & 0o022 != 0;
        let sticky = meta.mode() & 0o1000 != 0;
        let child_safe = !others_write || (sticky && (child_owner == me || child_owner == 0));
        if !owner_trusted || !child_safe {
            return Err(RunnerError::UnsafeAncestor {
                path,
                folder: folder.to_path_buf(),
                uid: meta.uid(),
                mode: meta.mode() & 0o7777,
            }
            .into());
        }
        child_owner = meta.uid();
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically: a fresh temporary file in the same folder, renamed into place.
fn write_atomic(path: &Path, bytes: &[u8], executable: bool) -> Result<(), CliError> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let err = |error: std::io::Error| {
        CliError::from(RunnerError::Write {
            path: path.to_path_buf(),
            error,
        })
    };
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map_or_else(Default::default, |n| n.to_string_lossy());
    let tmp = dir.join(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let mut options = std::fs::OpenOptions::new();
    options.write(true).create_new(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::mode(&mut options, if executable { 0o700 } else { 0o600 });
    #[cfg(not(unix))]
    let _ = executable;
    let result = options.open(&tmp).and_then(|mut f| {
        f.write_all(bytes)?;
        f.sync_all()
    });
    if let Err(e) = result.and_then(|()| std::fs::rename(&tmp, path)) {
        let _ = std::fs::remove_file(&tmp);
        return Err(err(e));
    }
    Ok(())
}

fn sha256_hex(parts: &[&[u8]]) -> String {
    let mut h = Sha256::new();
    for p in parts {
        // Length-prefixed, so that moving bytes between parts changes the hash.
        h.update((p.len() as u64).to_le_bytes());
        h.update(p);
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// The manifest of a cache entry.
#[derive(serde::Serialize, serde::Deserialize, PartialEq, Debug)]
struct EntryManifest {
    generator: String,
    source_sha256: String,
    binary_sha256: String,
}

const MANIFEST: &str = "entry.json";

fn runner_path(entry: &Path) -> PathBuf {
    entry.join(format!("runner{}", std::env::consts::EXE_SUFFIX))
}

/// Why a cache entry cannot be used as it is.
#[derive(Debug, PartialEq)]
enum EntryState {
    Valid,
    Missing,
    Invalid(String),
}

/// Checks a cache entry against the source it must have been built from.
fn check_entry(entry: &Path, source_sha256: &str) -> EntryState {
    let text = match std::fs::read(entry.join(MANIFEST)) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return EntryState::Missing,
        Err(e) => return EntryState::Invalid(format!("its manifest cannot be read ({e})")),
    };
    let manifest: EntryManifest = match serde_json::from_slice(&text) {
        Ok(m) => m,
        Err(e) => return EntryState::Invalid(format!("its manifest is corrupt ({e})")),
    };
    if manifest.generator != GENERATOR_VERSION || manifest.source_sha256 != source_sha256 {
        return EntryState::Invalid("it was built from other source (stale)".into());
    }
    match std::fs::read(runner_path(entry)) {
        Ok(binary) if sha256_hex(&[&binary]) == manifest.binary_sha256 => EntryState::Valid,
        Ok(_) => EntryState::Invalid("its binary does not match the manifest's hash".into()),
        Err(e) => EntryState::Invalid(format!("its binary cannot be read ({e})")),
    }
}

/// The runner's crate for `loaded` and `options`, before anything is written: its files, the cache key
/// (from every file the runner is generated from: the model's code, with the functions, scalars and links
/// of `options`, and `main.rs`) and the SHA-256 of the source the entry is built from.
struct RunnerSource {
    krate: String,
    files: Vec<(PathBuf, String)>,
    key: String,
    bin_name: String,
    source_sha256: String,
}

fn runner_source(loaded: &Loaded, options: &GenerateOptions) -> Result<RunnerSource, CliError> {
    let mut files = crate_files(loaded, options)?;
    let krate = crate_name(&loaded.robot.name);
    let model = loaded.model::<f64>(&options.model)?;
    let constrained = model.has_constraints();
    let scalars = options.scalars();
    let links = RunnerLinks::of(options, &model);
    let main = runner_main(
        &krate,
        &options.algorithms,
        constrained,
        &scalars,
        &links,
        options.lanes,
    )
    .map_err(RunnerError::from)?;
    files.push((PathBuf::from("src/main.rs"), main));
    let key_parts: Vec<&[u8]> = std::iter::once(GENERATOR_VERSION.as_bytes())
        .chain(
            files
                .iter()
                .flat_map(|(p, t)| [p.as_os_str().as_encoded_bytes(), t.as_bytes()]),
        )
        .collect();
    let key = sha256_hex(&key_parts)[..16].to_string();
    // The crate builds the runner as a `[[bin]]` beside its library; the binary's name carries the key,
    // so the shared target folder never hands one model's runner to another.
    let bin_name = format!("run_{key}");
    // The package's name carries the key too: runners of two models of one name (a scene's variants)
    // share the target folder, and cargo keys a path package's build by its name and version, not its
    // folder, so one runner could link the other's library (a stale build of another model). The
    // library keeps the crate's name, which main.rs uses.
    let mut manifest = Manifest::standalone(&format!("{krate}_{key}"), &loaded.robot.name);
    manifest.lib = Some(Library {
        name: krate.clone(),
        path: "src/lib.rs".into(),
    });
    if options.lanes > 0 {
        manifest = manifest.with_lanes();
    }
    manifest.bins.push(Binary {
        name: bin_name.clone(),
        path: "src/main.rs".into(),
    });
    let cargo_toml = manifest.to_toml().map_err(RunnerError::from)?;
    for (path, text) in &mut files {
        if path == Path::new("Cargo.toml") {
            *text = cargo_toml.clone();
        }
    }
    let source_parts: Vec<&[u8]> = files
        .iter()
        .flat_map(|(p, t)| [p.as_os_str().as_encoded_bytes(), t.as_bytes()])
        .collect();
    let source_sha256 = sha256_hex(&source_parts);
    Ok(RunnerSource {
        krate,
        files,
        key,
        bin_name,
        source_sha256,
    })
}

/// Writes (or reuses, after checking it) the runner for `loaded` and returns the path of its binary.
pub fn build_runner(loaded: &Loaded, options: &GenerateOptions) -> Result<PathBuf, CliError> {
    build_runner_in(loaded, options, None)
}

/// [`build_runner`] in the cache folder `folder` (checked as the usual one is), or the usual one.
pub fn build_runner_in(
    loaded: &Loaded,
    options: &GenerateOptions,
    folder: Option<&Path>,
) -> Result<PathBuf, CliError> {
    let RunnerSource {
        krate,
        files,
        key,
        bin_name,
        source_sha256,
    } = runner_source(loaded, options)?;

    let root = cache_root(folder)?;
    let entry = root.join(format!("{krate}-{key}"));
    match check_entry(&entry, &source_sha256) {
        EntryState::Valid => return Ok(runner_path(&entry)),
        EntryState::Missing => {}
        EntryState::Invalid(why) => super::output::note(&format!(
            "embedyn: the cached runner in {} is not usable: {why}; rebuilding it",
            entry.display()
        )),
    }
    for (rel, text) in &files {
        let path = entry.join(rel);
        create_private_dir(path.parent().unwrap_or(&entry))?;
        write_atomic(&path, text.as_bytes(), false)?;
    }
    super::output::note(&format!(
        "embedyn: compiling the generated code of {} (once; cached in {})",
        embedyn_codegen::names::code_span(&loaded.robot.name),
        entry.display()
    ));
    let target = root.join("target");
    create_private_dir(&target)?;
    cargo_build(&entry, &target, &bin_name)?;
    let built = target
        .join("release")
        .join(format!("{bin_name}{}", std::env::consts::EXE_SUFFIX));
    let binary = std::fs::read(&built).map_err(|error| RunnerError::BuiltUnreadable {
        path: built.clone(),
        error,
    })?;
    write_atomic(&runner_path(&entry), &binary, true)?;
    let record = EntryManifest {
        generator: GENERATOR_VERSION.into(),
        source_sha256: source_sha256.clone(),
        binary_sha256: sha256_hex(&[&binary]),
    };
    let json = serde_json::to_vec_pretty(&record).map_err(RunnerError::EntryManifest)?;
    write_atomic(&entry.join(MANIFEST), &json, false)?;
    match check_entry(&entry, &source_sha256) {
        EntryState::Valid => Ok(runner_path(&entry)),
        // Another run replaced the entry between our write and this check with a different binary;
        // never run what was not checked.
        EntryState::Missing | EntryState::Invalid(_) => {
            Err(RunnerError::EntryChanged { path: entry }.into())
        }
    }
}

/// `cargo build --release` of the runner: offline first (the usual case: libm is in cargo's cache), then
/// online once.
///
/// Cargo reads `.cargo/config.toml` in its working folder and in every folder above it, so it runs in the
/// file system's root (writable by the administrator only), never inside the cache: with the cache under
/// a shared folder (`EMBEDYN_CACHE_DIR=/tmp/mine`), another user could otherwise plant `/tmp/.cargo/config.toml`
/// and have cargo run a program of theirs. The crate is its own workspace, so nothing above it is read.
fn cargo_build(dir: &Path, target: &Path, bin_name: &str) -> Result<(), CliError> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let manifest = dir.join("Cargo.toml");
    let cwd = if cfg!(unix) { Path::new("/") } else { dir };
    let build = |offline: bool| {
        let mut cmd = Command::new(&cargo);
        cmd.args([
            "build",
            "--release",
            "--quiet",
            "--bin",
            bin_name,
            "--manifest-path",
        ])
        .arg(&manifest);
        if offline {
            cmd.arg("--offline");
        }
        cmd.current_dir(cwd)
            .env("CARGO_TARGET_DIR", target)
            .stdin(Stdio::null())
            .output()
            .map_err(|error| RunnerError::CannotRunCargo {
                cargo: cargo.clone(),
                error,
            })
    };
    if build(true)?.status.success() {
        return Ok(());
    }
    let retry = build(false)?;
    if retry.status.success() {
        Ok(())
    } else {
        Err(RunnerError::CompileFailed {
            stderr: String::from_utf8_lossy(&retry.stderr).into_owned(),
        }
        .into())
    }
}

/// What the runner prints per sample.
pub enum RowShape {
    /// One row of `len` numbers per input row (`eval`).
    Eval { len: usize },
    /// One row holding one positive number, the median ns per call (`bench`).
    Bench,
}

/// Runs the runner on `rows` (each q ‖ a ‖ b ‖ p: a configuration, two velocity-sized vectors, a second
/// configuration) and returns its output rows, each checked: as many rows as
/// asked for, each of the expected length, every entry a number.
pub fn run(
    binary: &Path,
    algo: &str,
    scalar: &str,
    shape: RowShape,
    rows: &[Vec<f64>],
) -> Result<Vec<Vec<f64>>, CliError> {
    let mode = match shape {
        RowShape::Eval { .. } => "eval",
        RowShape::Bench => "bench",
    };
    let mut text = format!("{algo} {scalar} {mode}\n");
    for r in rows {
        // `{:?}` prints the shortest decimal that reads back as the same double.
        let line: Vec<String> = r.iter().map(|x| format!("{x:?}")).collect();
        text.push_str(&line.join(" "));
        text.push('\n');
    }
    let mut child = Command::new(binary)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|error| RunnerError::CannotRun {
            binary: binary.to_path_buf(),
            error,
        })?;
    let stdin = child.stdin.take();
    // Fed from another thread, so that a runner writing before it has read everything cannot deadlock.
    let (written, out) = std::thread::scope(|s| {
        let feeder = s.spawn(move || match stdin {
            Some(mut w) => w.write_all(text.as_bytes()),
            None => Ok(()),
        });
        let out = child.wait_with_output();
        (feeder.join(), out)
    });
    let out = out.map_err(RunnerError::Wait)?;
    if !out.status.success() {
        return Err(RunnerError::Failed {
            status: out.status,
            stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        }
        .into());
    }
    match written {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(RunnerError::InputNotRead(e).into()),
        Err(_) => return Err(RunnerError::InputNotWritten.into()),
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    parse_rows(&stdout, rows.len(), &shape)
}

/// The runner's output as rows of numbers, checked against what was asked for.
fn parse_rows(stdout: &str, inputs: usize, shape: &RowShape) -> Result<Vec<Vec<f64>>, CliError> {
    let fail = |problem: RunnerOutputProblem| CliError::from(RunnerError::Output(problem));
    let (count, len) = match shape {
        RowShape::Eval { len } => (inputs, *len),
        RowShape::Bench => (1, 1),
    };
    let lines: Vec<&str> = stdout.split_terminator('\n').collect();
    if lines.len() != count {
        return Err(fail(RunnerOutputProblem::RowCount {
            printed: lines.len(),
            expected: count,
        }));
    }
    let mut out = Vec::with_capacity(count);
    for (i, line) in lines.iter().enumerate() {
        let row = line
            .split_whitespace()
            .map(|x| {
                x.parse::<f64>().map_err(|_| {
                    fail(RunnerOutputProblem::NotANumber {
                        text: x.to_string(),
                        row: i,
                    })
                })
            })
            .collect::<Result<Vec<f64>, _>>()?;
        if row.len() != len {
            return Err(fail(RunnerOutputProblem::RowLength {
                printed: row.len(),
                row: i,
                expected: len,
            }));
        }
        if matches!(shape, RowShape::Bench) && !(row[0].is_finite() && row[0] > 0.0) {
            return Err(fail(RunnerOutputProblem::BadTime { ns: row[0] }));
        }
        out.push(row);
    }
    Ok(out)
}

/// The functions the runner needs for the command line's `algorithms` on a model with or without
/// constraints: each, and the one that computes what the command reports for it when that is another
/// (`crba_independent` for `crba` with constraints).
pub fn runner_algorithms(algorithms: &[Algorithm], constrained: bool) -> Vec<Algorithm> {
    let mut needed = Vec::new();
    for &a in algorithms {
        for f in [a, a.reported_by(constrained)] {
            if !needed.contains(&f) {
                needed.push(f);
            }
        }
    }
    needed
}

/// What the runner's crate was generated with beyond its functions: how many links take wrenches (each
/// row then carries `6 K` numbers more: `f_ext` row-major) and the names of its frame functions.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunnerLinks {
    /// `WRENCH_LINKS.len()` (0: the crate has no wrench links, the rows their usual length).
    pub wrenches: usize,
    /// The generated `frame_<link>` functions, each its own arm of the runner, named as the function.
    pub frame_functions: Vec<String>,
}

impl RunnerLinks {
    /// What `options` generates for `model`: its wrench links (each once) and the names of its frame
    /// functions.
    pub fn of(options: &GenerateOptions, model: &embedyn_runtime::Model<f64>) -> RunnerLinks {
        fn once(names: &[String]) -> Vec<&str> {
            let mut out: Vec<&str> = Vec::new();
            for n in names {
                if !out.contains(&n.as_str()) {
                    out.push(n);
                }
            }
            out
        }
        RunnerLinks {
            wrenches: once(&options.links.wrenches).len(),
            frame_functions: embedyn_codegen::frame_function_names(
                model,
                &once(&options.links.frames),
            ),
        }
    }
}

/// The runner's arms for `algorithm`: the name the command line sends, then the code evaluating and
/// timing it ([`runner_calls`]); one arm per frame function for `frame`, none for a function the runner
/// does not run or whose links were not named.
fn runner_arms(
    algorithm: Algorithm,
    constrained: bool,
    links: &RunnerLinks,
) -> Vec<(String, TokenStream, TokenStream)> {
    use embedyn_codegen::algorithm::Parameter;
    let names = match algorithm.spec().parameter {
        Parameter::None => vec![algorithm.name().to_string()],
        Parameter::WrenchLinks if links.wrenches > 0 => vec![algorithm.name().to_string()],
        Parameter::WrenchLinks => Vec::new(),
        Parameter::Frame => links.frame_functions.clone(),
    };
    names
        .into_iter()
        .filter_map(|name| {
            let function = (algorithm.spec().parameter == Parameter::Frame).then_some(&name[..]);
            let (eval, bench) = runner_calls(algorithm, constrained, function)?;
            Some((name, eval, bench))
        })
        .collect()
}

/// The runner's code for `algorithm` (evaluating, timing), read from its descriptor: the function that
/// computes what the command line reports for it (`function` when given: a frame function's name),
/// called with `q` and its other inputs — up to two `NV`-vectors (`a`, `b`, in order), one more
/// configuration (`p`) and the wrenches `f_ext` (`w`) — and writing either one `NQ`- or `NV`-vector,
/// `NV × NV` or `NI × NI` matrix (the buffers the runner keeps), or several outputs of fixed, `NQ`,
/// `NV` or `NI` sizes (buffers of their own); the values are printed in the order of the outputs, then
/// the returned singularity measure if any. `None` for a function the runner does not run by its own
/// name: one that exists only for a model with constraints (the command line reaches
/// `crba_independent` as `crba`), or whose arguments or outputs the runner has no buffers for
/// (`kinematics`).
fn runner_calls(
    algorithm: Algorithm,
    constrained: bool,
    function: Option<&str>,
) -> Option<(TokenStream, TokenStream)> {
    use embedyn_codegen::algorithm::{Dim, Shape};
    if algorithm.needs_constraints() {
        return None;
    }
    let spec = algorithm.reported_by(constrained).spec();
    // The runner's own buffers for one output of the usual shapes (the code as it always was); buffers
    // of the function's own otherwise.
    let kept = match spec.outputs {
        [output] => match output.shape {
            Shape::Vector(Dim::Nv) => Some((quote!(out), quote!(out))),
            Shape::Vector(Dim::Nq) => Some((quote!(out_q), quote!(out_q))),
            Shape::Matrix(Dim::Nv, Dim::Nv) => Some((quote!(mat), quote!(mat.as_flattened()))),
            Shape::Matrix(Dim::Ni, Dim::Ni) => Some((quote!(mat_i), quote!(mat_i.as_flattened()))),
            _ => None,
        },
        _ => None,
    };
    let (first, rest) = spec.inputs.split_first()?;
    if first.len != Dim::Nq {
        return None;
    }
    // Each further input's slot of the row: the `NV`-vectors `a`, `b` in order, the configuration `p`,
    // the wrenches `w`.
    let (mut eval_args, mut bench_args) = (vec![quote!(q)], vec![quote!(black_box(&s.0))]);
    let mut vectors = [(quote!(a), quote!(&s.1)), (quote!(b), quote!(&s.2))].into_iter();
    let mut configurations = [(quote!(p), quote!(&s.3))].into_iter();
    let mut wrenches = [(quote!(w), quote!(&s.4))].into_iter();
    for input in rest {
        let (eval, bench) = match input.len {
            Dim::Nv => vectors.next()?,
            Dim::Nq => configurations.next()?,
            Dim::WrenchLinks => wrenches.next()?,
            _ => return None,
        };
        eval_args.push(eval);
        bench_args.push(bench);
    }
    let function = format_ident!("{}", function.unwrap_or(spec.name));
    let (setup, buffers, values) = match kept {
        Some((buffer, values)) => (
            quote!(),
            vec![quote!(&mut #buffer)],
            quote!(#values.iter().map(|&x| f64::from(x))),
        ),
        None => {
            let len = |d: Dim| -> Option<TokenStream> {
                Some(match d {
                    Dim::Nq => quote!(NQ),
                    Dim::Nv => quote!(NV),
                    Dim::Ni => quote!(NI),
                    Dim::Fixed(n) => {
                        let n = proc_macro2::Literal::usize_unsuffixed(n);
                        quote!(#n)
                    }
                    Dim::Frames | Dim::WrenchLinks | Dim::Scalar => return None,
                })
            };
            let (mut setup, mut buffers, mut values) = (Vec::new(), Vec::new(), Vec::new());
            for (k, output) in spec.outputs.iter().enumerate() {
                let buffer = format_ident!("o{}", k);
                let (init, flat) = match output.shape {
                    Shape::Vector(d) => {
                        let n = len(d)?;
                        (quote!([0.0 as S; #n]), quote!(#buffer.iter()))
                    }
                    Shape::Matrix(r, c) => {
                        let (r, c) = (len(r)?, len(c)?);
                        (
                            quote!([[0.0 as S; #c]; #r]),
                            quote!(#buffer.as_flattened().iter()),
                        )
                    }
                };
                setup.push(quote!(let mut #buffer = #init;));
                buffers.push(quote!(&mut #buffer));
                values.push(flat);
            }
            let (head, tail) = values.split_first()?;
            (
                quote!(#(#setup)*),
                buffers,
                quote!(#head #(.chain(#tail))*.map(|&x| f64::from(x))),
            )
        }
    };
    Some(if spec.returns_value(constrained) {
        (
            quote! {
                #setup
                let condition = m::#function(#(#eval_args,)* #(#buffers),*);
                emit(text, #values.chain([f64::from(condition)]));
            },
            quote! {
                #setup
                black_box(m::#function(#(#bench_args,)* #(#buffers),*));
            },
        )
    } else {
        (
            quote! { #setup m::#function(#(#eval_args,)* #(#buffers),*); emit(text, #values); },
            quote! { #setup m::#function(#(#bench_args,)* #(#buffers),*); },
        )
    })
}

/// The runner's `main.rs`, generated through `quote` and formatted like all generated code.
///
/// The algorithms whose lane module's `_batch` forms the runner times (scalar `f64xN`, mode `bench`).
pub(crate) const BATCH_TIMED: [&str; 3] = ["aba", "rnea", "crba"];

/// Protocol on stdin: a line `ALGO SCALAR eval|bench`, then one sample per line (q, then two vectors of
/// length NV, then a second configuration of length NQ, numbers separated by spaces; an empty line for a model without coordinates). Output: one
/// line per sample (eval), or one line with the median ns per call (bench); every number printed as an
/// f64 that reads back exactly. Bad input is an error on stderr with exit status 2, never a panic.
/// For a model with constraints, `crba` is `crba_independent` (`Xᵀ M X`, what the CLI reports), and
/// `aba` and `crba` print the singularity measure cond₁(Y1) after their values.
fn runner_main(
    krate: &str,
    algorithms: &[Algorithm],
    constrained: bool,
    scalars: &[&str],
    links: &RunnerLinks,
    lanes: usize,
) -> Result<String, RunnerSourceError> {
    let krate: syn::Ident =
        syn::parse_str(krate).map_err(|error| RunnerSourceError::NotAnIdentifier {
            krate: krate.to_string(),
            error,
        })?;
    let mut names = Vec::new();
    let mut eval_calls = Vec::new();
    let mut bench_calls = Vec::new();
    for &a in algorithms {
        for (name, eval, bench) in runner_arms(a, constrained, links) {
            names.push(name);
            eval_calls.push(eval);
            bench_calls.push(bench);
        }
    }
    // With wrench links, each row carries `f_ext` after the second configuration (`w`, the state's
    // fifth entry); without, the rows and the code are what they always were.
    let wrenches = links.wrenches > 0;
    let (wrench_count, state_type, state_wrenches, state_pattern, row_len) = if wrenches {
        let k = proc_macro2::Literal::usize_unsuffixed(links.wrenches);
        (
            quote! {
                /// `WRENCH_LINKS.len()`: each row ends with `f_ext`, `6 · WRENCHES` numbers row-major.
                const WRENCHES: usize = #k;
            },
            quote!(([S; NQ], [S; NV], [S; NV], [S; NQ], [[S; 6]; WRENCHES])),
            quote! {
                core::array::from_fn(|k| {
                    core::array::from_fn(|j| r[2 * NQ + 2 * NV + 6 * k + j] as S)
                }),
            },
            quote!((q, a, b, p, w)),
            quote!(2 * NQ + 2 * NV + 6 * WRENCHES),
        )
    } else {
        (
            quote!(),
            quote!(([S; NQ], [S; NV], [S; NV], [S; NQ])),
            quote!(),
            quote!((q, a, b, p)),
            quote!(2 * NQ + 2 * NV),
        )
    };
    // Only the scalar modules the crate has (a model whose constants do not fit f32 has no f32 module).
    let present: Vec<(&str, TokenStream)> = [("f64", quote!(f64)), ("f32", quote!(f32))]
        .into_iter()
        .filter(|(name, _)| scalars.contains(name))
        .collect();
    let mut dispatch: Vec<TokenStream> = present
        .iter()
        .map(|(name, _)| {
            let function = format_ident!("run_{}", name);
            quote!(#name => #function(algo, bench, &rows, &mut text)?,)
        })
        .collect();
    // With lanes, `bench` also times the f64 lane module's `_batch` forms over all the states at once
    // (scalar `f64xN` in the header), for BATCH_TIMED (`crba` is `crba_independent` with constraints).
    let batch = (lanes > 0 && scalars.contains(&"f64")).then(|| {
        let scalar_name = format!("f64x{lanes}");
        let module = format_ident!("f64x{}", lanes);
        let mut arms = Vec::new();
        for &a in algorithms {
            let call = match (a.name(), constrained) {
                ("aba", false) => quote!(m::aba_batch(&qs, &vs, &xs, &mut outs)),
                ("aba", true) => quote!(m::aba_batch(&qs, &vs, &xs, &mut outs, &mut measures)),
                ("rnea", _) => quote!(m::rnea_batch(&qs, &vs, &xs, &mut outs)),
                ("crba", false) => quote!(m::crba_batch(&qs, &mut mats)),
                ("crba_independent", true) => {
                    quote!(m::crba_independent_batch(&qs, &mut mats_i, &mut measures))
                }
                _ => continue,
            };
            // `crba` is what the command line names the reduced mass matrix too.
            let name = if a.name() == "crba_independent" { "crba" } else { a.name() };
            arms.push(quote!(#name => time(&mut || { black_box(#call); }),));
        }
        dispatch.push(quote!(#scalar_name => run_batch(algo, bench, &rows, &mut text)?,));
        quote! {
            /// Times the lane module's `_batch` forms over all the states in one call: ns per state.
            fn run_batch(algo: &str, bench: bool, rows: &[Vec<f64>], text: &mut String) -> Result<(), Refusal> {
                use #krate::#module as m;
                if !bench {
                    return Err(Refusal::UnknownMode("eval through the lanes".to_string()));
                }
                let n = rows.len();
                if n == 0 {
                    return Err(Refusal::NoStates);
                }
                let qs: Vec<[f64; NQ]> = rows.iter().map(|r| core::array::from_fn(|i| r[i])).collect();
                let vs: Vec<[f64; NV]> = rows.iter().map(|r| core::array::from_fn(|i| r[NQ + i])).collect();
                let xs: Vec<[f64; NV]> = rows.iter().map(|r| core::array::from_fn(|i| r[NQ + NV + i])).collect();
                let mut outs = vec![[0.0; NV]; n];
                let mut mats = vec![[[0.0; NV]; NV]; n];
                let mut mats_i = vec![[[0.0; NI]; NI]; n];
                let mut measures = vec![0.0; n];
                let _ = (&mut outs, &mut mats, &mut mats_i, &mut measures);
                let ns = match algo {
                    #(#arms)*
                    other => return Err(Refusal::UnknownAlgorithm(other.to_string())),
                };
                text.push_str(&format!("{:?}\n", ns / n as f64));
                Ok(())
            }
        }
    });
    let per_scalar = present.into_iter().map(|(name, scalar)| {
        let function = format_ident!("run_{}", name);
        let module = format_ident!("{}", name);
        quote! {
            /// Evaluates or times the functions of one scalar module; output is appended to `text`.
            fn #function(algo: &str, bench: bool, rows: &[Vec<f64>], text: &mut String) -> Result<(), Refusal> {
                use #krate::#module as m;
                type S = #scalar;
                let states: Vec<#state_type> = rows
                    .iter()
                    .map(|r| {
                        (
                            core::array::from_fn(|i| r[i] as S),
                            core::array::from_fn(|i| r[NQ + i] as S),
                            core::array::from_fn(|i| r[NQ + NV + i] as S),
                            core::array::from_fn(|i| r[NQ + 2 * NV + i] as S),
                            #state_wrenches
                        )
                    })
                    .collect();
                let mut out = [0.0 as S; NV];
                let mut out_q = [0.0 as S; NQ];
                let mut mat = [[0.0 as S; NV]; NV];
                let mut mat_i = [[0.0 as S; NI]; NI];
                let _ = (&mut out, &mut out_q, &mut mat, &mut mat_i);
                if bench {
                    let n = states.len();
                    if n == 0 {
                        return Err(Refusal::NoStates);
                    }
                    let mut k = 0usize;
                    let ns = match algo {
                        #(#names => time(&mut || {
                            k = (k + 1) % n;
                            let s = &states[k];
                            #bench_calls
                            black_box((&out, &out_q, &mat, &mat_i));
                        }),)*
                        other => return Err(Refusal::UnknownAlgorithm(other.to_string())),
                    };
                    text.push_str(&format!("{ns:?}\n"));
                } else {
                    for #state_pattern in &states {
                        let _ = #state_pattern;
                        match algo {
                            #(#names => { #eval_calls })*
                            other => return Err(Refusal::UnknownAlgorithm(other.to_string())),
                        }
                    }
                }
                Ok(())
            }
        }
    });
    // The timing loop `bench` uses for the interpreted solver, the same text.
    let time: TokenStream =
        syn::parse_str(super::bench::TIME_SOURCE).map_err(RunnerSourceError::TimingLoop)?;
    let file = quote! {
        //! Evaluates or times the generated functions for `embedyn eval --engine generated` and
        //! `embedyn bench` (protocol: see embedyn's `cli/runner.rs`).
        use std::hint::black_box;
        use std::io::{Read, Write};
        use #krate::{NI, NQ, NV};
        #wrench_count

        /// Appends one output line: every number as the f64 that reads back exactly.
        fn emit(text: &mut String, values: impl Iterator<Item = f64>) {
            let line: Vec<String> = values.map(|v| format!("{v:?}")).collect();
            text.push_str(&line.join(" "));
            text.push('\n');
        }

        #time

        /// Why the runner refuses its input (printed on stderr, exit status 2).
        enum Refusal {
            ReadStdin(std::io::Error),
            BadHeader(Vec<String>),
            UnknownMode(String),
            NotANumber { row: usize, text: String, error: std::num::ParseFloatError },
            RowLength { row: usize, numbers: usize },
            ScalarNotGenerated(String),
            UnknownAlgorithm(String),
            NoStates,
            WriteStdout(std::io::Error),
        }

        impl std::fmt::Display for Refusal {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                match self {
                    Refusal::ReadStdin(e) => write!(f, "cannot read stdin: {e}"),
                    Refusal::BadHeader(header) => {
                        write!(f, "bad header {header:?}, expected `ALGO SCALAR eval|bench`")
                    }
                    Refusal::UnknownMode(mode) => write!(f, "unknown mode {mode:?}"),
                    Refusal::NotANumber { row, text, error } => write!(f, "row {row}: {text:?}: {error}"),
                    Refusal::RowLength { row, numbers } => {
                        write!(f, "row {row} has {numbers} numbers, expected {}", #row_len)
                    }
                    Refusal::ScalarNotGenerated(scalar) => write!(f, "scalar {scalar:?} was not generated"),
                    Refusal::UnknownAlgorithm(algo) => write!(f, "unknown algorithm {algo:?}"),
                    Refusal::NoStates => write!(f, "bench needs at least one state"),
                    Refusal::WriteStdout(e) => write!(f, "cannot write stdout: {e}"),
                }
            }
        }

        #(#per_scalar)*

        #batch

        fn run() -> Result<(), Refusal> {
            let mut input = String::new();
            std::io::stdin()
                .read_to_string(&mut input)
                .map_err(Refusal::ReadStdin)?;
            let mut lines = input.split_terminator('\n');
            let header: Vec<&str> = lines.next().unwrap_or("").split_whitespace().collect();
            let [algo, scalar, mode] = header[..] else {
                return Err(Refusal::BadHeader(header.iter().map(|w| w.to_string()).collect()));
            };
            let bench = match mode {
                "bench" => true,
                "eval" => false,
                other => return Err(Refusal::UnknownMode(other.to_string())),
            };
            let mut rows = Vec::new();
            for (i, line) in lines.enumerate() {
                let row = line
                    .split_whitespace()
                    .map(|x| {
                        x.parse::<f64>().map_err(|error| Refusal::NotANumber {
                            row: i,
                            text: x.to_string(),
                            error,
                        })
                    })
                    .collect::<Result<Vec<f64>, Refusal>>()?;
                if row.len() != #row_len {
                    return Err(Refusal::RowLength { row: i, numbers: row.len() });
                }
                rows.push(row);
            }
            let mut text = String::new();
            match scalar {
                #(#dispatch)*
                other => return Err(Refusal::ScalarNotGenerated(other.to_string())),
            }
            std::io::stdout()
                .write_all(text.as_bytes())
                .map_err(Refusal::WriteStdout)
        }

        fn main() -> std::process::ExitCode {
            match run() {
                Ok(()) => std::process::ExitCode::SUCCESS,
                Err(e) => {
                    let _ = writeln!(std::io::stderr(), "runner: {e}");
                    std::process::ExitCode::from(2)
                }
            }
        }
    };
    Ok(format_tokens(&file)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runner_rows_are_checked() {
        let eval = |s: &str, n: usize, len: usize| parse_rows(s, n, &RowShape::Eval { len });
        assert_eq!(
            eval("1 2\n3 4\n", 2, 2).unwrap(),
            vec![vec![1.0, 2.0], vec![3.0, 4.0]]
        );
        // No coordinates: one empty row per sample.
        assert_eq!(eval("\n\n", 2, 0).unwrap(), vec![Vec::<f64>::new(); 2]);
        for (out, message) in [
            ("", "printed 0 rows for 2 expected"),
            ("1 2\n", "printed 1 rows for 2 expected"),
            ("1 2\n3\n", "printed 1 numbers in row 1, expected 2"),
            ("1 2\n3 4 5\n", "printed 3 numbers in row 1, expected 2"),
            ("1 2\n3 x\n", "printed \"x\" in row 1, not a number"),
            ("1 2\n3 4\n5 6\n", "printed 3 rows for 2 expected"),
        ] {
            let e = eval(out, 2, 2).unwrap_err().to_string();
            assert!(e.contains(message), "{out:?}: {e}");
        }
        assert!(matches!(
            eval("1 2\n", 2, 2),
            Err(CliError::Runner(RunnerError::Output(
                RunnerOutputProblem::RowCount {
                    printed: 1,
                    expected: 2
                }
            )))
        ));
        assert_eq!(
            parse_rows("12.5\n", 64, &RowShape::Bench).unwrap(),
            vec![vec![12.5]]
        );
        for out in ["", "NaN\n", "0\n", "1 2\n", "1\n2\n"] {
            assert!(parse_rows(out, 64, &RowShape::Bench).is_err(), "{out:?}");
        }
    }

    #[test]
    fn cache_entries_are_checked_before_use() {
        let dir = std::env::temp_dir().join(format!("embedyn-entry-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        create_private_dir(&dir).unwrap();
        assert_eq!(check_entry(&dir, "abc"), EntryState::Missing);
        let binary = b"\x7fELF pretend binary".to_vec();
        write_atomic(&runner_path(&dir), &binary, true).unwrap();
        let good = EntryManifest {
            generator: GENERATOR_VERSION.into(),
            source_sha256: "abc".into(),
            binary_sha256: sha256_hex(&[&binary]),
        };
        let write_manifest = |m: &[u8]| write_atomic(&dir.join(MANIFEST), m, false).unwrap();
        write_manifest(&serde_json::to_vec(&good).unwrap());
        assert_eq!(check_entry(&dir, "abc"), EntryState::Valid);
        // Stale: built from other source.
        assert!(matches!(check_entry(&dir, "abd"), EntryState::Invalid(w) if w.contains("stale")));
        // Truncated binary.
        write_atomic(&runner_path(&dir), &binary[..4], true).unwrap();
        assert!(matches!(check_entry(&dir, "abc"), EntryState::Invalid(w) if w.contains("hash")));
        write_atomic(&runner_path(&dir), &binary, true).unwrap();
        // Corrupt and truncated manifests.
        let json = serde_json::to_vec(&good).unwrap();
        write_manifest(&json[..json.len() / 2]);
        assert!(
            matches!(check_entry(&dir, "abc"), EntryState::Invalid(w) if w.contains("corrupt"))
        );
        write_manifest(b"\xff\xfe garbage");
        assert!(matches!(check_entry(&dir, "abc"), EntryState::Invalid(_)));
        // No temporary files are left behind.
        let names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(names.iter().all(|n| !n.contains(".tmp-")), "{names:?}");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode(&dir), 0o700);
            assert_eq!(mode(&runner_path(&dir)), 0o700);
            assert_eq!(mode(&dir.join(MANIFEST)), 0o600);
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_runner_runs_what_the_command_line_reports() {
        use Algorithm::{Aba, Crba, CrbaIndependent, Rnea};
        assert_eq!(
            runner_algorithms(&[Aba, Rnea, Crba], false),
            [Aba, Rnea, Crba]
        );
        assert_eq!(
            runner_algorithms(&[Aba, Rnea, Crba], true),
            [Aba, Rnea, Crba, CrbaIndependent]
        );
        // `crba` of a model with constraints runs `crba_independent` and prints its measure after M.
        let src = runner_main(
            "arm_dynamics",
            &[Crba],
            true,
            &["f64"],
            &RunnerLinks::default(),
            0,
        )
        .unwrap();
        assert!(
            src.contains("let condition = m::crba_independent(q, &mut mat_i);"),
            "{src}"
        );
        // Functions the runner has no buffers or name for get no arm.
        let src = runner_main(
            "arm_dynamics",
            &Algorithm::ALL,
            false,
            &["f64"],
            &RunnerLinks::default(),
            0,
        )
        .unwrap();
        for absent in ["kinematics", "complete", "embedding"] {
            assert!(!src.contains(&format!("m::{absent}")), "{absent}: {src}");
        }
        assert!(src.contains("m::minv(q, &mut mat);"), "{src}");
    }

    /// The links a runner's functions are generated for (wrench links, frame, reference) reach its
    /// source, hence its cache key: a runner generated for other links is never reused.
    #[test]
    fn the_links_reach_the_cache_key() {
        use embedyn_codegen::LinkOptions;
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/loops/four_bar_internal.urdf");
        let loaded = embedyn_codegen::load(&path).unwrap();
        let source = |algorithms: Vec<Algorithm>, links: LinkOptions| {
            let options = GenerateOptions {
                algorithms,
                exact: true,
                f32: false,
                links,
                ..Default::default()
            };
            let s = runner_source(&loaded, &options).unwrap();
            let main = s
                .files
                .iter()
                .find(|(p, _)| p.ends_with("main.rs"))
                .unwrap();
            (s.key, main.1.clone())
        };
        let frame = |reference| LinkOptions {
            frames: vec!["tip".into()],
            reference,
            ..Default::default()
        };
        let (local, main) = source(
            vec![Algorithm::Frame],
            frame(embedyn_codegen::Reference::Local),
        );
        assert!(main.contains("\"frame_tip\" =>"), "{main}");
        assert!(
            main.contains("m::frame_tip(q, a, &mut o0, &mut o1, &mut o2);"),
            "{main}"
        );
        let (world, _) = source(
            vec![Algorithm::Frame],
            frame(embedyn_codegen::Reference::World),
        );
        assert_ne!(local, world);
        let wrenches = |links: &[&str]| LinkOptions {
            wrenches: links.iter().map(|l| l.to_string()).collect(),
            ..Default::default()
        };
        let (one, main) = source(vec![Algorithm::AbaExt], wrenches(&["crank"]));
        assert!(main.contains("const WRENCHES: usize = 1;"), "{main}");
        assert!(main.contains("m::aba_ext(q, a, b, w, &mut out)"), "{main}");
        let (two, main) = source(vec![Algorithm::AbaExt], wrenches(&["crank", "tip"]));
        assert!(main.contains("const WRENCHES: usize = 2;"), "{main}");
        assert_ne!(one, two);
        // Without links, the runner is what it always was: no wrenches in its rows.
        let (_, main) = source(vec![Algorithm::Aba], LinkOptions::default());
        assert!(!main.contains("WRENCHES"), "{main}");
    }

    #[test]
    fn runner_source_parses_for_every_algorithm() {
        for constrained in [false, true] {
            let src = runner_main(
                "arm_dynamics",
                &Algorithm::ALL,
                constrained,
                &["f64", "f32"],
                &RunnerLinks::default(),
                0,
            )
            .unwrap();
            assert!(src.contains("use arm_dynamics::{NI, NQ, NV};"), "{src}");
            assert!(
                !src.contains("unwrap()") && !src.contains("panic!"),
                "{src}"
            );
        }
        assert!(runner_main(
            "not an identifier",
            &Algorithm::ALL,
            false,
            &["f64"],
            &RunnerLinks::default(),
            0
        )
        .is_err());
    }
}
