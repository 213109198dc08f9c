//! The locked-down Rhai engine: takes the scene's folder, the project's `scripts/` folder,
//! limits and a cancel flag, and gives an `Engine` that can only import modules from those
//! two folders, has no `eval`, stops after a bounded number of operations, call depth and
//! data sizes, and stops when the cancel flag is raised. Rhai itself has no file or network
//! access; the only file access is the module resolver below (read-only, `.rhai` files).

use crate::util::ShowPath;
use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use rhai::module_resolvers::ModuleResolver;
use rhai::{Dynamic, Engine, EvalAltResult, Module, Position, Scope, Shared};

use super::budget::Budget;
use crate::util::lock;

type SharedModule = Shared<Module>;

/// What a cancelled evaluation ends with (any other termination is a limit).
pub(super) const CANCELLED: &str = "cancelled";

/// Bounds on what a script may use.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    pub max_operations: u64,
    pub max_call_levels: usize,
    pub max_expr_depth: usize,
    pub max_function_expr_depth: usize,
    pub max_string_size: usize,
    pub max_array_size: usize,
    pub max_map_size: usize,
    pub max_modules: usize,
    /// Bytes an evaluation may allocate in all (its strings, arrays and maps together),
    /// when the program measures allocations (`set_allocation_probe`).
    pub max_memory: usize,
    /// Seconds an evaluation may run: a bound on what the operation limit does not count
    /// (the size check after each change to a value, which walks all of it).
    pub max_seconds: u64,
}

impl Default for Limits {
    /// Generous for scenes (keyframe lists of thousands of entries), small enough that a
    /// runaway loop stops within about a second.
    fn default() -> Self {
        Limits {
            max_operations: 5_000_000,
            max_call_levels: 64,
            max_expr_depth: 64,
            max_function_expr_depth: 32,
            max_string_size: 1 << 20,
            // Rhai counts these over a value and everything nested in it: a list of keys
            // (each a map with an `at` array) holds three map entries and two array
            // entries per key. A million of each lets 300,000 keys through; the memory
            // budget bounds the rest.
            max_array_size: 1_000_000,
            max_map_size: 1_000_000,
            max_modules: 64,
            max_memory: 256 << 20,
            max_seconds: 60,
        }
    }
}

/// A fresh engine with the sandbox applied (no scene functions yet).
pub fn sandboxed_engine(
    resolver: SandboxResolver,
    limits: &Limits,
    cancel: Arc<AtomicBool>,
    budget: Budget,
) -> Engine {
    let mut engine = Engine::new();
    engine
        .set_max_operations(limits.max_operations)
        .set_max_call_levels(limits.max_call_levels)
        .set_max_expr_depths(limits.max_expr_depth, limits.max_function_expr_depth)
        .set_max_string_size(limits.max_string_size)
        .set_max_array_size(limits.max_array_size)
        .set_max_map_size(limits.max_map_size)
        .set_max_modules(limits.max_modules)
        .set_module_resolver(resolver)
        .disable_symbol("eval");
    // A scene gives the same frames on every run, in bounded time: no clock, no waiting.
    // Functions registered here are found before the standard package's.
    let refuse = |name: &str| -> Result<(), Box<rhai::EvalAltResult>> {
        Err(format!("`{name}` is not available in scenes: a scene gives the same frames on every run").into())
    };
    engine
        .register_fn("sleep", move |_: rhai::FLOAT| refuse("sleep"))
        .register_fn("sleep", move |_: rhai::INT| refuse("sleep"))
        .register_fn("timestamp", move || refuse("timestamp"));
    engine.on_progress(move |operations| {
        if cancel.load(Ordering::Relaxed) {
            Some(Dynamic::from(CANCELLED))
        } else {
            budget
                .exceeded()
                .or_else(|| budget.late(operations))
                .map(Dynamic::from)
        }
    });
    // Script output goes to stderr so stdout stays machine-readable.
    engine.on_print(|text| eprint_line!("{text}"));
    engine.on_debug(|text, _, pos| eprint_line!("[{pos}] {text}"));
    engine
}

/// Resolves `import "name"` to `name.rhai` in the scene's folder, then in the project's
/// `scripts/` folder — nowhere else: absolute paths and `..` are refused, and the resolved
/// file must (after following links) lie inside one of the two folders.
#[derive(Clone, Debug)]
pub struct SandboxResolver {
    roots: Vec<PathBuf>,
    /// Import name → file it resolved to (for error positions), shared with [`ModuleFiles`].
    files: Arc<Mutex<HashMap<String, PathBuf>>>,
    /// Successfully evaluated modules by file.
    modules: Arc<Mutex<HashMap<PathBuf, SharedModule>>>,
    /// Modules being evaluated, outermost first: an import of one of them is a cycle.
    loading: Arc<Mutex<Vec<PathBuf>>>,
}

impl SandboxResolver {
    pub fn new(scene_dir: &Path, scripts_dir: Option<&Path>) -> Self {
        let roots = std::iter::once(scene_dir)
            .chain(scripts_dir)
            .filter_map(|d| d.canonicalize().ok())
            .collect();
        SandboxResolver {
            roots,
            files: Arc::default(),
            modules: Arc::default(),
            loading: Arc::default(),
        }
    }

    /// How an error names a module file: relative to the folder it was found in.
    fn short_name(&self, file: &Path) -> String {
        self.roots
            .iter()
            .find_map(|root| file.strip_prefix(root).ok())
            .unwrap_or(file)
            .shown()
            .to_string()
    }

    /// Refuses an import of a module still being evaluated, naming the chain
    /// (`a.rhai → b.rhai → a.rhai`); else marks `file` as being evaluated.
    fn enter(&self, file: &Path) -> Result<(), String> {
        let mut loading = lock(&self.loading);
        if let Some(first) = loading.iter().position(|f| f == file) {
            let chain: Vec<String> = loading[first..]
                .iter()
                .chain(std::iter::once(&file.to_path_buf()))
                .map(|f| self.short_name(f))
                .collect();
            return Err(format!("import cycle: {}", chain.join(" → ")));
        }
        loading.push(file.to_path_buf());
        Ok(())
    }

    /// A shared view of the resolved modules, for mapping import names to files.
    pub fn module_files(&self) -> ModuleFiles {
        ModuleFiles {
            files: self.files.clone(),
            modules: self.modules.clone(),
        }
    }

    fn find(&self, name: &str) -> Result<PathBuf, String> {
        let relative = Path::new(name);
        let plain = relative
            .components()
            .all(|c| matches!(c, Component::Normal(_)));
        if !plain || name.is_empty() {
            return Err(format!(
                "import `{name}` must be a plain relative name (no absolute paths, no `..`)"
            ));
        }
        let file_name = if relative.extension().is_some() {
            relative.to_path_buf()
        } else {
            relative.with_extension("rhai")
        };
        let (mut escaped, mut broken) = (None, None);
        for root in &self.roots {
            let candidate = root.join(&file_name);
            let Ok(found) = candidate.canonicalize() else {
                // A link that resolves to no file (dangling, or a loop) is there all the same.
                if candidate.symlink_metadata().is_ok() {
                    broken = broken.or(Some(candidate));
                }
                continue;
            };
            if found.starts_with(root) {
                if let Some(problem) = crate::util::not_a_file(&found) {
                    return Err(format!("module `{name}` {problem} ({})", found.shown()));
                }
                return Ok(found);
            }
            escaped = escaped.or(Some(found));
        }
        Err(match (escaped, broken) {
            (Some(target), _) => format!(
                "module `{name}` is a link to {}, outside the scene's folder and the project's \
                 scripts/ folder",
                target.shown()
            ),
            (None, Some(link)) => format!(
                "module `{name}` is a symbolic link to nothing (or a loop of links): {}",
                link.shown()
            ),
            (None, None) => format!(
                "module `{name}` not found in the scene's folder or the project's scripts/ folder"
            ),
        })
    }
}

/// Import name → resolved file, filled as modules are imported.
#[derive(Clone, Debug)]
pub struct ModuleFiles {
    files: Arc<Mutex<HashMap<String, PathBuf>>>,
    modules: Arc<Mutex<HashMap<PathBuf, SharedModule>>>,
}

impl ModuleFiles {
    pub fn file_of(&self, name: &str) -> Option<PathBuf> {
        lock(&self.files).get(name).cloned()
    }

    /// Every module file imported so far (directly or by another module), sorted.
    pub fn files(&self) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = lock(&self.modules).keys().cloned().collect();
        files.sort();
        files
    }
}

impl ModuleResolver for SandboxResolver {
    fn resolve(
        &self,
        engine: &Engine,
        _source: Option<&str>,
        path: &str,
        pos: Position,
    ) -> Result<SharedModule, Box<EvalAltResult>> {
        let file = self
            .find(path)
            .map_err(|message| EvalAltResult::ErrorRuntime(message.into(), pos))?;
        lock(&self.files).insert(path.to_string(), file.clone());
        if let Some(module) = lock(&self.modules).get(&file) {
            return Ok(module.clone());
        }
        self.enter(&file)
            .map_err(|message| EvalAltResult::ErrorRuntime(message.into(), pos))?;
        let result = self.load(engine, path, &file, pos);
        lock(&self.loading).pop();
        result
    }
}

impl SandboxResolver {
    /// Reads, compiles and evaluates the module `path` found at `file`, and keeps it.
    fn load(
        &self,
        engine: &Engine,
        path: &str,
        file: &Path,
        pos: Position,
    ) -> Result<SharedModule, Box<EvalAltResult>> {
        let text = super::source::read_source(file).map_err(|e| {
            EvalAltResult::ErrorRuntime(
                format!("cannot read module {}: {e}", file.shown()).into(),
                pos,
            )
        })?;
        let mut ast = engine
            .compile(&text)
            .map_err(|e| EvalAltResult::ErrorInModule(path.to_string(), e.into(), pos))?;
        ast.set_source(file.to_string_lossy().as_ref());
        let module: SharedModule = Module::eval_ast_as_new(Scope::new(), &ast, engine)
            .map_err(|e| EvalAltResult::ErrorInModule(path.to_string(), e, pos))?
            .into();
        lock(&self.modules).insert(file.to_path_buf(), module.clone());
        Ok(module)
    }
}
