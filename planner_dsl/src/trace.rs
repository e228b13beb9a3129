//! The execution trace and the outcome of a run (serialisable).

use crate::error::{RuntimeError, Span};
use map_core::Trajectory;
use serde::{Deserialize, Serialize};

/// One robot function library call, as it happened.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceEntry {
    /// Library function name.
    pub function: String,
    /// Arguments as given (object records as their fields).
    pub args: Vec<serde_json::Value>,
    /// What the call returned (`null` for actions).
    pub result: serde_json::Value,
    /// Robot pose `[x, y, heading]` after the call.
    pub pose_after: [f64; 3],
    /// Wall time of the call, microseconds.
    pub duration_us: u64,
    /// Where in the script the call was made.
    pub span: Span,
    /// Something the user should know (e.g. stopped short of an obstacle).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub warning: Option<String>,
    /// Why the call failed (the plan stopped here).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// What a run did: every library call, what the plan said, and the error that
/// stopped it, if any (the trace and the robot's trajectory are kept up to there).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunOutcome {
    /// Every library call in order.
    pub trace: Vec<TraceEntry>,
    /// Texts passed to `say`, in order.
    pub said: Vec<String>,
    /// Why the plan stopped early, if it did.
    pub error: Option<RuntimeError>,
    /// Rhai operations used.
    pub operations: u64,
    /// Wall time of the whole run, microseconds.
    pub elapsed_us: u64,
    /// Robot pose `[x, y, heading]` at the end.
    pub final_pose: [f64; 3],
}

impl RunOutcome {
    /// Whether the plan ran to its end without error.
    pub fn is_ok(&self) -> bool {
        self.error.is_none()
    }

    /// The instances the plan's selections picked, in call order, once each: every
    /// object a library call returned (`get_obj(...)`, an anchor of `near:` included),
    /// whether or not the robot then stopped at it.
    pub fn selected(&self) -> Vec<u32> {
        let mut out = Vec::new();
        for e in &self.trace {
            if let Ok(r) = crate::value::ObjectRecord::deserialize(&e.result) {
                if !out.contains(&r.id) {
                    out.push(r.id);
                }
            }
        }
        out
    }
}

/// A dry run's result: the outcome and the preview trajectory of the robot's copy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DryRun {
    /// What the run did.
    pub outcome: RunOutcome,
    /// Where the copy of the robot went (the real robot did not move).
    pub trajectory: Trajectory,
}
