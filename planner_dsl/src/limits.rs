//! Hard limits on what a plan may do. The same values hold in debug and release
//! builds (Rhai's own defaults differ between them; we set every one explicitly).

use serde::{Deserialize, Serialize};
use std::time::Duration;

/// Every limit a plan runs under. [`Limits::default`] suits LLM-written plans: a
/// typical plan uses a few hundred operations and a handful of robot actions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// Rhai operations (each expression step, loop iteration, call) per run.
    pub max_operations: u64,
    /// Nesting of script-defined function calls (bounds recursion).
    pub max_call_levels: usize,
    /// Nesting depth of expressions at top level (checked when compiling).
    pub max_expr_depth: usize,
    /// Nesting depth of expressions inside script-defined functions.
    pub max_function_expr_depth: usize,
    /// Longest string, in bytes.
    pub max_string_size: usize,
    /// Longest array, in elements (nested arrays count in full).
    pub max_array_size: usize,
    /// Largest object map, in entries.
    pub max_map_size: usize,
    /// Variables alive at once.
    pub max_variables: usize,
    /// Functions a script may define.
    pub max_functions: usize,
    /// Robot function library calls per run (bounds trace and trajectory growth).
    pub max_library_calls: usize,
    /// Longest script accepted, in bytes (checked before parsing).
    pub max_source_bytes: usize,
    /// Wall-clock budget for the script's own work, not counting the time spent
    /// inside robot function library calls (a real robot's moves take minutes).
    pub deadline: Duration,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_operations: 200_000,
            max_call_levels: 32,
            max_expr_depth: 48,
            max_function_expr_depth: 32,
            max_string_size: 8 * 1024,
            max_array_size: 10_000,
            max_map_size: 1_000,
            max_variables: 256,
            max_functions: 64,
            max_library_calls: 200,
            max_source_bytes: 64 * 1024,
            deadline: Duration::from_millis(500),
        }
    }
}

impl Limits {
    /// Applies the engine-level limits to a Rhai engine (modules are compiled out:
    /// the crate builds rhai with `no_module`, so `import` cannot even be parsed).
    pub(crate) fn apply(&self, engine: &mut rhai::Engine) {
        engine
            .set_max_operations(self.max_operations.max(1))
            .set_max_call_levels(self.max_call_levels)
            .set_max_expr_depths(
                self.max_expr_depth.max(1),
                self.max_function_expr_depth.max(1),
            )
            .set_max_string_size(self.max_string_size.max(1))
            .set_max_array_size(self.max_array_size.max(1))
            .set_max_map_size(self.max_map_size.max(1))
            .set_max_variables(self.max_variables.max(1))
            .set_max_functions(self.max_functions);
    }
}
