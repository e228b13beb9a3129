//! `ivlmap noise-study`: arguments, and the driver around [`eval::noise::noise_study`].

use std::path::PathBuf;

use eval::noise::{noise_study, noise_table, NoiseStudyOptions};
use eval::suite::load_nav_suite;

use crate::error::{write_json, CliError};

/// Arguments of `ivlmap noise-study`.
#[derive(Debug, clap::Args)]
pub struct NoiseStudyArgs {
    /// Navigation suite(s) (.nav.jsonl) whose tasks carry `reference` plans.
    #[arg(required = true)]
    pub suites: Vec<PathBuf>,
    /// Noise rates (comma-separated), each applied to every kind in --kinds.
    #[arg(long, value_delimiter = ',', default_value = "0,0.05,0.1,0.2,0.3")]
    pub noise: Vec<f64>,
    /// First seed; seeds SEED..SEED+SEEDS are averaged.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// How many seeds to average.
    #[arg(long, default_value_t = 5)]
    pub seeds: usize,
    /// Noise kinds the rate applies to (comma-separated): label_flip, fragment, merge,
    /// drop, colour_shift.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "label_flip,fragment,merge,drop,colour_shift"
    )]
    pub kinds: Vec<String>,
    /// Write the study (rows per rate and method, per-seed figures, map effects) as JSON.
    #[arg(long)]
    pub report: Option<PathBuf>,
}

/// Runs `ivlmap noise-study`: loads the suites, runs the study, prints the table and
/// writes the report.
///
/// # Errors
/// [`CliError::Input`] for a bad suite, plan, rate or kind; [`CliError::Output`] when
/// the report cannot be written.
pub fn noise_study_cli(args: &NoiseStudyArgs) -> Result<(), CliError> {
    let mut tasks = Vec::new();
    let mut names = Vec::new();
    for p in &args.suites {
        tasks.extend(load_nav_suite(p).map_err(CliError::input)?);
        names.push(p.file_name().map_or_else(
            || p.display().to_string(),
            |n| n.to_string_lossy().to_string(),
        ));
    }
    let opts = NoiseStudyOptions {
        rates: args.noise.clone(),
        seed: args.seed,
        seeds: args.seeds,
        kinds: args.kinds.iter().map(|k| k.trim().to_string()).collect(),
    };
    let study = noise_study(&names, &tasks, &opts, &mut |step| {
        tracing::info!("noise study: {step}");
    })
    .map_err(CliError::Input)?;
    print!("{}", noise_table(&study));
    if let Some(p) = &args.report {
        write_json(p, &study)?;
        println!("report: {}", p.display());
    }
    Ok(())
}
