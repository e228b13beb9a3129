//! The evaluation report (formats.md) and the summary table printed after a run.

use std::fmt::Write as _;
use std::path::Path;

use map_core::Trajectory;
use serde::{Deserialize, Serialize};

use super::score::{nav_scores, ratio, SideStop};

/// One evaluated case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseResult {
    /// The case id from the suite.
    pub id: String,
    /// Extraction: the tuples matched `expected`; navigation: every subgoal reached.
    pub ok: bool,
    /// What the system produced: the tuples (extraction), or `{"tuples", "script"}`
    /// (navigation); `null` when it produced nothing.
    pub got: serde_json::Value,
    /// Time the language layer took for this case (backend calls included), ms.
    pub latency_ms: u64,
    /// Why the case failed to produce or run a plan, if it did.
    pub error: Option<String>,
    /// The instruction (additive, for reading the report alone).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instruction: Option<String>,
    /// Navigation: the trajectory of the run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trajectory: Option<Trajectory>,
    /// Navigation: per subgoal, whether it was reached.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reached: Option<Vec<bool>>,
    /// Chat: one result per turn, in order.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub turns: Option<Vec<crate::chat::TurnResult>>,
    /// Navigation with a model: the re-asks the language layer made for this case (a
    /// question or refusal comes after one); additive.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reasks: Option<u32>,
    /// Navigation with a model, where the first answer did not stand (a re-ask, a
    /// question or a refusal followed): whether that first answer, run as it was, would
    /// have reached every subgoal (the checks re-asked a right plan); additive.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub first_answer_ok: Option<bool>,
    /// Navigation: the subgoals the task's reference plan reaches by a move to one side
    /// of the object, with the call the run reached each by (see
    /// [`SideStop`]); absent when there are none; additive.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sides: Option<Vec<SideStop>>,
}

/// The report's summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Cases run.
    pub total: usize,
    /// Cases ok.
    pub ok: usize,
    /// ok / total.
    pub accuracy: f64,
    /// Median latency, ms (nearest rank).
    pub latency_ms_p50: u64,
    /// 95th percentile latency, ms (nearest rank).
    pub latency_ms_p95: u64,
    /// Navigation: T_1..T_K.
    #[serde(rename = "T", default, skip_serializing_if = "Option::is_none")]
    pub t: Option<Vec<f64>>,
    /// Navigation: share of subgoals reached.
    #[serde(rename = "SR", default, skip_serializing_if = "Option::is_none")]
    pub sr: Option<f64>,
    /// Chat: share of turns whose every subgoal was reached.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub turn_accuracy: Option<f64>,
    /// Chat: share of dialogues whose every turn was.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dialogue_success: Option<f64>,
    /// Share of the cases that report `reasks` whose first answer did not stand (a
    /// re-ask was made); additive.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reask_rate: Option<f64>,
    /// Of the cases whose first answer did not stand, how many first answers would have
    /// reached every subgoal as they were (`first_answer_ok`); additive.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reasked_first_ok: Option<usize>,
    /// Navigation: subgoals whose reference stop is a move to one side of the object
    /// (`sides`), over all cases; additive.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub side_stops: Option<usize>,
    /// Of those, how many the run reached with the same side function; additive.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub side_stops_kept: Option<usize>,
}

/// The report file of formats.md.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// The suite file name.
    pub suite: String,
    /// The backend name (`llama`, `openai`, `replay`, ...).
    pub backend: String,
    /// The model (path or name).
    pub model: String,
    /// The prompt variant (label or folder).
    pub prompts: String,
    /// `ivlmap` or `vlmap` (the baseline); additive field.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<String>,
    /// Every case, in suite order.
    pub cases: Vec<CaseResult>,
    /// The figures.
    pub summary: Summary,
}

impl Report {
    /// A report from its cases; the summary is computed (navigation figures when any
    /// case carries `reached`).
    #[must_use]
    pub fn new(
        suite: String,
        backend: String,
        model: String,
        prompts: String,
        method: Option<String>,
        cases: Vec<CaseResult>,
    ) -> Report {
        let summary = summarise(&cases);
        Report {
            suite,
            backend,
            model,
            prompts,
            method,
            cases,
            summary,
        }
    }

    /// Writes the report as pretty JSON.
    ///
    /// # Errors
    /// The I/O error, with the path.
    pub fn write(&self, path: &Path) -> Result<(), std::io::Error> {
        let text = serde_json::to_string_pretty(self).map_err(std::io::Error::other)?;
        std::fs::write(path, text + "\n").map_err(|e| {
            std::io::Error::new(
                e.kind(),
                format!("{}: cannot write report: {e}", path.display()),
            )
        })
    }

    /// A short label for table columns: method and prompt variant.
    #[must_use]
    pub fn label(&self) -> String {
        let m = self.method.as_deref().unwrap_or("ivlmap");
        format!("{m} {}/{}", self.backend, self.prompts)
    }
}

/// Nearest-rank percentile of `values` (0 when empty); `p` in (0, 100].
#[must_use]
pub fn percentile(values: &[u64], p: f64) -> u64 {
    if values.is_empty() {
        return 0;
    }
    let mut v = values.to_vec();
    v.sort_unstable();
    let rank = ((p / 100.0) * v.len() as f64).ceil() as usize;
    v[rank.clamp(1, v.len()) - 1]
}

/// The summary of a list of cases.
#[must_use]
pub fn summarise(cases: &[CaseResult]) -> Summary {
    let lat: Vec<u64> = cases.iter().map(|c| c.latency_ms).collect();
    let ok = cases.iter().filter(|c| c.ok).count();
    let reached: Vec<Vec<bool>> = cases.iter().filter_map(|c| c.reached.clone()).collect();
    let nav = (!reached.is_empty()).then(|| nav_scores(&reached));
    let turns: Vec<&crate::chat::TurnResult> = cases
        .iter()
        .filter_map(|c| c.turns.as_ref())
        .flatten()
        .collect();
    let chat = (!turns.is_empty()).then(|| (turns.iter().filter(|t| t.ok()).count(), turns.len()));
    let reasks: Vec<u32> = cases.iter().filter_map(|c| c.reasks).collect();
    let sides: Vec<&SideStop> = cases
        .iter()
        .filter_map(|c| c.sides.as_ref())
        .flatten()
        .collect();
    let reask_rate = (!reasks.is_empty())
        .then(|| ratio(reasks.iter().filter(|&&k| k > 0).count(), reasks.len()));
    Summary {
        total: cases.len(),
        ok,
        accuracy: ratio(ok, cases.len()),
        latency_ms_p50: percentile(&lat, 50.0),
        latency_ms_p95: percentile(&lat, 95.0),
        t: nav.as_ref().map(|n| n.t.clone()),
        sr: nav.map(|n| n.sr),
        turn_accuracy: chat.map(|(ok, n)| ratio(ok, n)),
        dialogue_success: chat.map(|_| ratio(ok, cases.len())),
        reask_rate,
        reasked_first_ok: cases.iter().any(|c| c.first_answer_ok.is_some()).then(|| {
            cases
                .iter()
                .filter(|c| c.first_answer_ok == Some(true))
                .count()
        }),
        side_stops: (!sides.is_empty()).then_some(sides.len()),
        side_stops_kept: (!sides.is_empty()).then(|| sides.iter().filter(|s| s.kept()).count()),
    }
}

/// A plain-text table of the reports side by side (one column per report).
#[must_use]
pub fn summary_table(reports: &[Report]) -> String {
    let mut rows: Vec<(String, Vec<String>)> = vec![
        ("".into(), reports.iter().map(Report::label).collect()),
        (
            "model".into(),
            reports.iter().map(|r| short_model(&r.model)).collect(),
        ),
        (
            "cases".into(),
            reports
                .iter()
                .map(|r| r.summary.total.to_string())
                .collect(),
        ),
        (
            "ok".into(),
            reports
                .iter()
                .map(|r| format!("{}/{}", r.summary.ok, r.summary.total))
                .collect(),
        ),
        (
            "accuracy".into(),
            reports
                .iter()
                .map(|r| format!("{:.3}", r.summary.accuracy))
                .collect(),
        ),
    ];
    let k_max = reports
        .iter()
        .filter_map(|r| r.summary.t.as_ref().map(Vec::len))
        .max()
        .unwrap_or(0);
    for k in 0..k_max {
        rows.push((
            format!("T_{}", k + 1),
            reports
                .iter()
                .map(|r| {
                    r.summary
                        .t
                        .as_ref()
                        .and_then(|t| t.get(k))
                        .map_or("-".into(), |v| format!("{v:.3}"))
                })
                .collect(),
        ));
    }
    if reports.iter().any(|r| r.summary.sr.is_some()) {
        rows.push((
            "SR".into(),
            reports
                .iter()
                .map(|r| r.summary.sr.map_or("-".into(), |v| format!("{v:.3}")))
                .collect(),
        ));
    }
    for (name, get) in [
        (
            "turn accuracy",
            (|r: &Report| r.summary.turn_accuracy) as fn(&Report) -> Option<f64>,
        ),
        ("dialogue success", |r: &Report| r.summary.dialogue_success),
        ("re-asked", |r: &Report| r.summary.reask_rate),
    ] {
        if reports.iter().any(|r| get(r).is_some()) {
            rows.push((
                name.into(),
                reports
                    .iter()
                    .map(|r| get(r).map_or("-".into(), |v| format!("{v:.3}")))
                    .collect(),
            ));
        }
    }
    if reports.iter().any(|r| r.summary.reasked_first_ok.is_some()) {
        rows.push((
            "re-asked, first right".into(),
            reports
                .iter()
                .map(|r| {
                    r.summary
                        .reasked_first_ok
                        .map_or("-".into(), |n| n.to_string())
                })
                .collect(),
        ));
    }
    if reports.iter().any(|r| r.summary.side_stops.is_some()) {
        rows.push((
            "side stops kept".into(),
            reports
                .iter()
                .map(
                    |r| match (r.summary.side_stops_kept, r.summary.side_stops) {
                        (Some(k), Some(n)) => format!("{k}/{n}"),
                        _ => "-".into(),
                    },
                )
                .collect(),
        ));
    }
    rows.push((
        "latency p50 ms".into(),
        reports
            .iter()
            .map(|r| r.summary.latency_ms_p50.to_string())
            .collect(),
    ));
    rows.push((
        "latency p95 ms".into(),
        reports
            .iter()
            .map(|r| r.summary.latency_ms_p95.to_string())
            .collect(),
    ));
    let w0 = rows.iter().map(|(h, _)| h.len()).max().unwrap_or(0);
    let widths: Vec<usize> = (0..reports.len())
        .map(|i| {
            rows.iter()
                .map(|(_, c)| c[i].chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out = String::new();
    for (h, cells) in &rows {
        let _ = write!(out, "{h:<w0$}");
        for (c, w) in cells.iter().zip(&widths) {
            let _ = write!(out, "  {c:>w$}");
        }
        out.push('\n');
    }
    out
}

fn short_model(m: &str) -> String {
    Path::new(m)
        .file_name()
        .map_or_else(|| m.to_string(), |f| f.to_string_lossy().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case(id: &str, ok: bool, ms: u64, reached: Option<Vec<bool>>) -> CaseResult {
        CaseResult {
            id: id.into(),
            ok,
            got: serde_json::Value::Null,
            latency_ms: ms,
            error: None,
            instruction: None,
            trajectory: None,
            reached,
            turns: None,
            reasks: None,
            first_answer_ok: None,
            sides: None,
        }
    }

    #[test]
    fn the_reask_rate_counts_cases_whose_first_answer_did_not_stand() {
        let mut cases: Vec<CaseResult> = (0..4)
            .map(|i| case(&format!("n{i}"), true, 1, Some(vec![true])))
            .collect();
        assert_eq!(summarise(&cases).reask_rate, None, "no model, no rate");
        for (c, k) in cases.iter_mut().zip([0, 1, 0, 0]) {
            c.reasks = Some(k);
        }
        assert_eq!(summarise(&cases).reasked_first_ok, None);
        cases[1].first_answer_ok = Some(true);
        let s = summarise(&cases);
        assert_eq!(s.reask_rate, Some(0.25));
        assert_eq!(s.reasked_first_ok, Some(1));
        let table = summary_table(&[Report {
            suite: "x.nav.jsonl".into(),
            backend: "llama".into(),
            model: "m.gguf".into(),
            prompts: "builtin".into(),
            method: None,
            cases,
            summary: s,
        }]);
        assert!(
            table.contains("re-asked") && table.contains("0.250"),
            "{table}"
        );
        assert!(
            table
                .lines()
                .any(|l| l.starts_with("re-asked, first right") && l.ends_with(" 1")),
            "{table}"
        );
    }

    #[test]
    fn chat_reports_turn_accuracy_and_dialogue_success() {
        let turn = |ok: bool| crate::chat::TurnResult {
            say: "x".into(),
            tuples: None,
            script: None,
            trajectory: Trajectory::default(),
            question: None,
            error: None,
            reached: vec![ok],
            latency_ms: 1,
        };
        let mut a = case("d1", true, 5, None);
        a.turns = Some(vec![turn(true), turn(true)]);
        let mut b = case("d2", false, 7, None);
        b.turns = Some(vec![turn(true), turn(false), turn(true)]);
        let s = summarise(&[a, b]);
        assert_eq!(s.turn_accuracy, Some(0.8));
        assert_eq!(s.dialogue_success, Some(0.5));
        assert!(s.t.is_none(), "a chat report has no T_k");
        let r = Report::new(
            "d.chat.jsonl".into(),
            "b".into(),
            "m".into(),
            "p".into(),
            None,
            vec![],
        );
        assert!(r.summary.turn_accuracy.is_none());
    }

    #[test]
    fn percentiles_are_nearest_rank() {
        let v: Vec<u64> = (1..=20).collect();
        assert_eq!(percentile(&v, 50.0), 10);
        assert_eq!(percentile(&v, 95.0), 19);
        assert_eq!(percentile(&[7], 95.0), 7);
        assert_eq!(percentile(&[], 50.0), 0);
    }

    #[test]
    fn report_json_has_the_formats_md_fields() {
        let r = Report::new(
            "x.nav.jsonl".into(),
            "replay".into(),
            "m.gguf".into(),
            "default".into(),
            None,
            vec![
                case("t1", true, 100, Some(vec![true, true])),
                case("t2", false, 300, Some(vec![true, false])),
            ],
        );
        let v = serde_json::to_value(&r).unwrap();
        for k in ["suite", "backend", "model", "prompts", "cases", "summary"] {
            assert!(v.get(k).is_some(), "{k}");
        }
        assert!(v.get("method").is_none());
        let s = &v["summary"];
        assert_eq!(s["total"], 2);
        assert_eq!(s["ok"], 1);
        assert_eq!(s["accuracy"], 0.5);
        assert_eq!(s["T"], serde_json::json!([1.0, 0.5]));
        assert_eq!(s["SR"], 0.75);
        assert_eq!(s["latency_ms_p50"], 100);
        assert_eq!(v["cases"][1]["reached"], serde_json::json!([true, false]));
        let table = summary_table(&[r.clone(), r]);
        assert!(table.contains("T_2") && table.contains("SR"), "{table}");
        // An extraction report has no navigation figures.
        let e = Report::new(
            "a".into(),
            "b".into(),
            "c".into(),
            "d".into(),
            None,
            vec![case("p", true, 5, None)],
        );
        let v = serde_json::to_value(&e).unwrap();
        assert!(v["summary"].get("T").is_none() && v["summary"].get("SR").is_none());
    }
}
