//! Time the grid planner on an obstacle grid and a list of start/goal pairs, as
//! `bench/compare_vlmaps.py` needs it; prints JSON on stdout.
//!
//! `cargo run --release -p map_core --example plan_bench -- GRID.npy QUERIES.json`
//!
//! GRID.npy: uint8, 1 = occupied, already inflated. QUERIES.json: `{"cell_size_m":
//! 0.05, "pairs": [{"start": [row, col], "goal": [row, col]}, ...]}`.

use std::time::Instant;

use map_core::npy::read_npy;
use map_core::{Cell, Grid, GridPlanner};

/// Time the grid planner on GRID.npy and QUERIES.json.
#[derive(Debug, clap::Parser)]
struct Args {
    /// uint8 obstacle grid, 1 = occupied, already inflated.
    grid: std::path::PathBuf,
    /// `{"cell_size_m": 0.05, "pairs": [{"start": [row, col], "goal": [row, col]}, ...]}`.
    queries: std::path::PathBuf,
    /// Warm-query repetitions.
    #[arg(default_value_t = 5)]
    repeats: usize,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Args {
        grid: grid_path,
        queries: q_path,
        repeats,
    } = clap::Parser::parse();
    let q: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&q_path)?)?;
    let cell_size = q["cell_size_m"].as_f64().unwrap_or(0.05);
    let cell = |v: &serde_json::Value| -> Option<Cell> {
        Some(Cell::new(
            v.get(0)?.as_u64()? as usize,
            v.get(1)?.as_u64()? as usize,
        ))
    };
    let pairs: Vec<(Cell, Cell)> = q["pairs"]
        .as_array()
        .ok_or("queries: no `pairs` array")?
        .iter()
        .map(|p| {
            Ok((
                cell(&p["start"]).ok_or("bad start")?,
                cell(&p["goal"]).ok_or("bad goal")?,
            ))
        })
        .collect::<Result<_, &str>>()?;
    let (&(s0, g0), _) = pairs.split_first().ok_or("queries: no pairs")?;

    let t0 = Instant::now();
    let raw: Grid<u8> = read_npy(&grid_path)?;
    let grid = raw.map(|&v| v != 0);
    let t_load = Instant::now();
    let planner = GridPlanner::new(grid);
    let t_new = Instant::now();
    let first = planner.plan(s0, g0)?;
    let t_first = Instant::now();

    let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
    // warm-up pass, then the median of `repeats` timed runs per pair
    for &(s, g) in &pairs {
        planner.plan(s, g)?;
    }
    let mut warm = Vec::new();
    let mut lengths = Vec::new();
    let mut raw_lengths = Vec::new();
    let mut waypoints = Vec::new();
    for &(s, g) in &pairs {
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..repeats.max(1) {
            let a = Instant::now();
            let p = planner.plan(s, g)?;
            times.push(ms(a, Instant::now()));
            last = Some(p);
        }
        times.sort_by(f64::total_cmp);
        warm.push(times[times.len() / 2]);
        let p = last.ok_or("no run")?;
        lengths.push(p.smoothed_len * cell_size);
        raw_lengths.push(p.raw_len * cell_size);
        waypoints.push(
            p.waypoints
                .iter()
                .map(|c| [c.row, c.col])
                .collect::<Vec<_>>(),
        );
    }
    let out = serde_json::json!({
        "load_ms": ms(t0, t_load),
        "new_ms": ms(t_load, t_new),
        "first_query_ms": ms(t_new, t_first),
        "first_path_total_ms": ms(t_load, t_first),
        "first_path_len_m": first.smoothed_len * cell_size,
        "warm_ms": warm,
        "lengths_m": lengths,
        "raw_lengths_m": raw_lengths,
        "waypoints": waypoints,
    });
    println!("{out}");
    Ok(())
}
