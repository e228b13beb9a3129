//! # planner_dsl: the sandboxed plan language (work in progress)
