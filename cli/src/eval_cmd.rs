//! `ivlmap eval`: suites against backends and prompt variants, with progress bars,
//! reports and the side-by-side table.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use agent::{PlanOptions, Prompts};
use eval::report::{summary_table, CaseResult, Report};
use eval::suite::{load_extract_suite, load_nav_suite, SuiteKind};
use eval::{run_extract, run_nav, Method};
use llm::LlmBackend;

use crate::args::Baseline;
use crate::backend::{open_backend, BackendChoice};
use crate::error::CliError;

fn progress(len: usize, label: &str) -> indicatif::ProgressBar {
    let pb = indicatif::ProgressBar::new(len as u64);
    let style = indicatif::ProgressStyle::with_template(
        "{prefix} [{bar:30}] {pos}/{len} {msg} ({elapsed}, eta {eta})",
    )
    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
    .progress_chars("=> ");
    pb.set_style(style);
    pb.set_prefix(label.to_string());
    pb
}

pub(crate) fn eval(
    suite: &Path,
    choices: &[BackendChoice],
    prompt_dirs: &[PathBuf],
    report_path: &Path,
    baseline: Option<Baseline>,
    plan_options: &PlanOptions,
) -> Result<ExitCode, CliError> {
    let kind = SuiteKind::from_path(suite).map_err(CliError::input)?;
    let variants: Vec<(String, Prompts)> = if prompt_dirs.is_empty() {
        vec![(
            "builtin".into(),
            crate::retrieval::with_retrieval(Prompts::builtin(), plan_options),
        )]
    } else {
        prompt_dirs
            .iter()
            .map(|d| {
                Ok((
                    d.display().to_string(),
                    crate::retrieval::with_retrieval(
                        Prompts::load(d).map_err(CliError::input)?,
                        plan_options,
                    ),
                ))
            })
            .collect::<Result<_, CliError>>()?
    };
    let method = match baseline {
        None => Method::Ivlmap,
        Some(Baseline::Vlmap) => Method::Vlmap,
        Some(Baseline::Reference) => Method::Reference,
    };
    if kind != SuiteKind::Nav && baseline.is_some() {
        return Err(CliError::Input(
            "--baseline applies to navigation suites (.nav.jsonl) only".into(),
        ));
    }
    let suite_name = suite.file_name().map_or_else(
        || suite.display().to_string(),
        |n| n.to_string_lossy().to_string(),
    );
    let (extract_cases, nav_tasks, dialogues) = match kind {
        SuiteKind::Extract => (
            load_extract_suite(suite).map_err(CliError::input)?,
            Vec::new(),
            Vec::new(),
        ),
        SuiteKind::Nav => (
            Vec::new(),
            load_nav_suite(suite).map_err(CliError::input)?,
            Vec::new(),
        ),
        SuiteKind::Chat => (
            Vec::new(),
            Vec::new(),
            eval::suite::load_chat_suite(suite).map_err(CliError::input)?,
        ),
    };
    let n = extract_cases.len() + nav_tasks.len() + dialogues.len();
    let mut reports = Vec::new();
    // The reference method needs no model: one run, no backend.
    let backend_runs: Vec<Option<&BackendChoice>> = if method == Method::Reference {
        vec![None]
    } else {
        choices.iter().map(Some).collect()
    };
    for choice in backend_runs {
        let backend = match choice {
            Some(c) => Some(open_backend(c)?),
            None => None,
        };
        let (bname, model) = match &backend {
            Some(b) => (b.name().to_string(), b.model().to_string()),
            None => ("none".to_string(), "none".to_string()),
        };
        for (label, prompts) in &variants {
            let pb = progress(n, &format!("{} {bname} {label}", method.name()));
            let mut tick = |c: &CaseResult| {
                pb.set_message(format!("{} {}", c.id, if c.ok { "ok" } else { "miss" }));
                pb.inc(1);
            };
            let cases = match kind {
                SuiteKind::Extract => match &backend {
                    Some(b) => {
                        run_extract(&extract_cases, b.as_ref(), prompts, plan_options, &mut tick)
                    }
                    None => Vec::new(),
                },
                SuiteKind::Chat => match &backend {
                    Some(b) => eval::chat::run_chat(
                        &dialogues,
                        b.as_ref(),
                        prompts,
                        plan_options,
                        &mut tick,
                    ),
                    None => Vec::new(),
                },
                SuiteKind::Nav => run_nav(
                    &nav_tasks,
                    method,
                    backend.as_deref().map(|b| b as &dyn LlmBackend),
                    prompts,
                    plan_options,
                    &mut tick,
                ),
            };
            pb.finish_and_clear();
            let m = (kind == SuiteKind::Nav).then(|| method.name().to_string());
            reports.push(Report::new(
                suite_name.clone(),
                bname.clone(),
                model.clone(),
                label.clone(),
                m,
                cases,
            ));
        }
    }
    let paths = report_paths(report_path, &reports);
    for (r, p) in reports.iter().zip(&paths) {
        r.write(p).map_err(|e| CliError::output(p, e))?;
    }
    print!("{}", summary_table(&reports));
    for p in &paths {
        println!("report: {}", p.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// One run: the path as given; several: `<stem>.<n>-<label>.json` beside it.
fn report_paths(path: &Path, reports: &[Report]) -> Vec<PathBuf> {
    if reports.len() <= 1 {
        return vec![path.to_path_buf()];
    }
    let stem = path
        .file_stem()
        .map_or_else(|| "report".to_string(), |s| s.to_string_lossy().to_string());
    let dir = path.parent().unwrap_or_else(|| Path::new(""));
    reports
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let tail = Path::new(&r.prompts)
                .file_name()
                .map_or_else(|| r.prompts.clone(), |f| f.to_string_lossy().to_string());
            let label: String = format!("{}-{}", r.backend, tail)
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            dir.join(format!("{stem}.{}-{label}.json", i + 1))
        })
        .collect()
}
