//! Code generation as a library, for bikedyn's own `build.rs` and for users'
//! crates (as `prost-build` does for protobuf).
//!
//! A user's `build.rs` declares models with [`crate::model`] and calls
//! [`generate`]; their crate then pulls the registry in and uses the
//! `bikedyn-runtime` crate on the generated types:
//!
//! ```ignore
//! // build.rs
//! fn main() {
//!     let model = my_models::double_pendulum().expect("valid model");
//!     let out = std::path::PathBuf::from(std::env::var_os("OUT_DIR").unwrap());
//!     bikedyn_modeler::codegen::generate(&[model], &out).unwrap_or_else(|e| panic!("{e}"));
//! }
//! // src/lib.rs
//! include!(concat!(env!("OUT_DIR"), "/models.rs"));
//! ```
//!
//! [`generate`] writes, into the output folder, one `<model>.rs` per model
//! (its functions and its `MultibodyModel` implementation), `models.rs` (the
//! registry: a module per model, `MODELS`, `SOURCES`, `with_model` and the
//! unit struct `Registry`, which implements
//! `bikedyn_runtime::registry::ModelRegistry` for them) and
//! `codegen_report.json` (derivation time and operation counts).

#[cfg(feature = "derive")]
use crate::derive::derive;
#[cfg(feature = "derive")]
use crate::emit::emit;
use crate::model::Model;
#[cfg(feature = "derive")]
use crate::registry::emit_registry;
use crate::registry::EmitError;
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Duration;
#[cfg(feature = "derive")]
use std::time::Instant;

/// Why code generation failed.
#[derive(Debug)]
pub enum GenerateError {
    Emit { model: String, source: EmitError },
    Io { path: PathBuf, source: std::io::Error },
    DuplicateModel(String),
}
impl fmt::Display for GenerateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GenerateError::Emit { model, source } => write!(f, "model `{model}`: {source}"),
            GenerateError::Io { path, source } => write!(f, "writing {}: {source}", path.display()),
            GenerateError::DuplicateModel(n) => write!(f, "two models are named `{n}`"),
        }
    }
}
impl std::error::Error for GenerateError {}

/// Figures of one generated model.
#[derive(Clone, Debug)]
pub struct ModelReport {
    pub model: String,
    pub derivation: Duration,
    /// Derivation plus emission.
    pub total: Duration,
    /// Operations of the individual functions before and after
    /// common-subexpression elimination (`all_quantities` excluded: it
    /// repeats them).
    pub operations_before: usize,
    pub operations_after: usize,
    /// Per function: (name, before, after, transcendental calls after).
    pub functions: Vec<(&'static str, usize, usize, usize)>,
}

/// Figures of a whole generation.
#[derive(Clone, Debug)]
pub struct CodegenReport {
    pub models: Vec<ModelReport>,
    pub total: Duration,
}

impl CodegenReport {
    /// JSON (hand-written: the modeler has no serde dependency).
    pub fn to_json(&self) -> String {
        let models: Vec<String> = self
            .models
            .iter()
            .map(|m| {
                let functions: Vec<String> = m
                    .functions
                    .iter()
                    .map(|(n, b, a, _)| {
                        format!("{{\"name\":\"{n}\",\"operations_before\":{b},\"operations_after\":{a}}}")
                    })
                    .collect();
                format!(
                    "{{\"model\":\"{}\",\"derivation_s\":{},\"derivation_and_emission_s\":{},\"operations_before\":{},\"operations_after\":{},\"functions\":[{}]}}",
                    m.model,
                    m.derivation.as_secs_f64(),
                    m.total.as_secs_f64(),
                    m.operations_before,
                    m.operations_after,
                    functions.join(",")
                )
            })
            .collect();
        format!(
            "{{\"total_s\":{},\"budget_s\":30,\"models\":[{}]}}\n",
            self.total.as_secs_f64(),
            models.join(",")
        )
    }
}

#[cfg(feature = "derive")]
fn write(path: PathBuf, text: &str) -> Result<(), GenerateError> {
    // Rewrite only on change, so that cargo does not recompile unchanged code.
    if std::fs::read_to_string(&path).is_ok_and(|old| old == text) {
        return Ok(());
    }
    std::fs::write(&path, text).map_err(|source| GenerateError::Io { path, source })
}

#[cfg(feature = "derive")]
/// Exclusive use of Symbolica on this machine while it is held.
///
/// Symbolica's non-commercial licence allows one Symbolica thread; two
/// derivations at once (parallel test threads, or two build scripts that
/// cargo runs in parallel, such as bikedyn's and an example crate's) abort
/// the process. The guard takes an in-process mutex and an exclusive lock
/// on a file in the system's temporary folder, and releases both on drop.
/// It is reentrant: a thread that holds it gets an empty guard.
///
/// Within one process the guard is not enough: Symbolica keeps its state
/// with the thread that first used it, and another thread that starts using
/// it aborts the process even after the first one released the guard (its
/// thread may not have finished yet, as with test threads). Code that may
/// run on several threads of one process (tests) uses Symbolica through
/// [`on_symbolica_thread`] instead.
pub struct SymbolicaGuard {
    _file: Option<std::fs::File>,
    _mutex: Option<std::sync::MutexGuard<'static, ()>>,
}

#[cfg(feature = "derive")]
thread_local! {
    /// Whether this thread holds a [`SymbolicaGuard`] (for reentrancy).
    static HOLDS_SYMBOLICA: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

#[cfg(feature = "derive")]
impl Drop for SymbolicaGuard {
    fn drop(&mut self) {
        if self._mutex.is_some() {
            HOLDS_SYMBOLICA.with(|h| h.set(false));
        }
    }
}

#[cfg(feature = "derive")]
/// Wait for exclusive use of Symbolica (see [`SymbolicaGuard`]).
pub fn symbolica_guard() -> SymbolicaGuard {
    if HOLDS_SYMBOLICA.with(|h| h.get()) {
        return SymbolicaGuard {
            _file: None,
            _mutex: None,
        };
    }
    static MUTEX: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let mutex = MUTEX.lock().unwrap_or_else(|e| e.into_inner());
    let path = std::env::temp_dir().join("bikedyn-symbolica.lock");
    // If the lock file cannot be used (read-only temp folder), the mutex
    // still serialises this process.
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .ok()
        .filter(|f| match f.try_lock() {
            Ok(()) => true,
            Err(std::fs::TryLockError::WouldBlock) => {
                // Say why nothing happens: a wait can last minutes.
                eprintln!(
                    "bikedyn: waiting for Symbolica: another derivation on this machine holds it ({}; Symbolica's licence allows one thread per user)",
                    path.display()
                );
                f.lock().is_ok()
            }
            Err(std::fs::TryLockError::Error(_)) => false,
        });
    HOLDS_SYMBOLICA.with(|h| h.set(true));
    SymbolicaGuard {
        _file: file,
        _mutex: Some(mutex),
    }
}

#[cfg(feature = "derive")]
/// Run `f` on this process's one Symbolica thread (started on first use,
/// alive until the process exits), holding the [`SymbolicaGuard`], and
/// return its result; a panic in `f` is resumed in the caller. Every use of
/// Symbolica from code that may run on several threads (parallel tests)
/// goes through here, so that one thread only ever touches Symbolica.
pub fn on_symbolica_thread<R: Send + 'static>(f: impl FnOnce() -> R + Send + 'static) -> R {
    type Job = Box<dyn FnOnce() + Send>;
    static JOBS: std::sync::OnceLock<std::sync::mpsc::Sender<Job>> = std::sync::OnceLock::new();
    let jobs = JOBS.get_or_init(|| {
        let (tx, rx) = std::sync::mpsc::channel::<Job>();
        std::thread::Builder::new()
            .name("symbolica".into())
            .spawn(move || {
                for job in rx {
                    job();
                }
            })
            .expect("start the Symbolica thread");
        tx
    });
    let (done, result) = std::sync::mpsc::sync_channel(1);
    let job: Job = Box::new(move || {
        let _one_symbolica = symbolica_guard();
        let _ = done.send(std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)));
    });
    jobs.send(job).expect("the Symbolica thread runs");
    match result.recv().expect("the Symbolica thread answers") {
        Ok(r) => r,
        Err(panic) => std::panic::resume_unwind(panic),
    }
}

#[cfg(feature = "derive")]
/// Derive and emit every model into `out_dir` (see the module docs).
pub fn generate(models: &[Model], out_dir: &Path) -> Result<CodegenReport, GenerateError> {
    let _one_symbolica = symbolica_guard();
    let start = Instant::now();
    let mut seen = std::collections::BTreeSet::new();
    for m in models {
        if !seen.insert(m.name.as_str()) {
            return Err(GenerateError::DuplicateModel(m.name.clone()));
        }
    }
    let mut reports = Vec::new();
    for model in models {
        let t0 = Instant::now();
        let derived = derive(model);
        let emitted = emit(&derived).map_err(|source| GenerateError::Emit {
            model: model.name.clone(),
            source,
        })?;
        write(out_dir.join(format!("{}.rs", model.name)), &emitted.source)?;
        let singles = || emitted.reports.iter().filter(|r| r.name != "all_quantities");
        reports.push(ModelReport {
            model: model.name.clone(),
            derivation: derived.elapsed,
            total: t0.elapsed(),
            operations_before: singles().map(|r| r.before.total()).sum(),
            operations_after: singles().map(|r| r.after.total()).sum(),
            functions: emitted
                .reports
                .iter()
                .map(|r| (r.name, r.before.total(), r.after.total(), r.after.transcendental))
                .collect(),
        });
    }
    let registry = emit_registry(models).map_err(|source| GenerateError::Emit {
        model: "registry".into(),
        source,
    })?;
    write(out_dir.join("models.rs"), &registry)?;
    let report = CodegenReport {
        models: reports,
        total: start.elapsed(),
    };
    write(out_dir.join("codegen_report.json"), &report.to_json())?;
    Ok(report)
}

/// What a crate's `build.rs` calls: with the `derive` feature, derive and
/// emit every model into `out_dir` ([`generate`]); without it, take each
/// model's committed file from `snapshots` when its inputs hash matches
/// ([`crate::snapshot::from_snapshots`]), else stop with the models that
/// changed and the command that re-derives them. Returns the derivation
/// report when the models were derived.
pub fn build(
    models: &[Model],
    snapshots: &Path,
    out_dir: &Path,
) -> Result<Option<CodegenReport>, Box<dyn std::error::Error>> {
    #[cfg(feature = "derive")]
    {
        let _ = snapshots;
        Ok(Some(generate(models, out_dir)?))
    }
    #[cfg(not(feature = "derive"))]
    {
        crate::snapshot::from_snapshots(models, snapshots, out_dir)?;
        Ok(None)
    }
}
