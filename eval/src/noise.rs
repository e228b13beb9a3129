//! Noise study: how navigation degrades when the map comes from imperfect
//! perception. For each noise rate and seed, each scene's perfect perception
//! outputs ([`PerceptionInputs::from_scene`]) are corrupted
//! ([`PerceptionInputs::with_noise`]: label flips, fragmented, merged and dropped
//! masks, colour shifts), a map is built from them ([`build_map`]),
//! and every task of the suite runs on that map from its start pose:
//!
//! - `ivlmap`: the task's hand-written `reference` plan (ordinals, colours, orders:
//!   what the IVLMap pipeline outputs when the language step is right);
//! - `vlmap`: the VLMaps behaviour, [`vlmap_script`] of the tuples read off the
//!   reference plan (each `get_obj_attributes` name and each `move_to_object`
//!   region, in order): the nearest instance of each category.
//!
//! The stops are scored against the TRUE scene ([`reached`] on the task's own map):
//! a stop at a merged blob or a fragment counts only if it is within 1 m of the
//! right object. No model runs; results are deterministic given the seeds. Figures
//! are T_1..T_4 and SR averaged over seeds (each seed's figure is over all tasks).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Arc;

use map_build::perception::{build_map, BuildConfig, NoiseLog, PerceptionInputs, PerceptionNoise};
use map_core::planner::inflate_m;
use map_core::{GridPlanner, IvlMap, Robot, Scene, SimRobot};
use planner_dsl::{Limits, Plan};
use serde::Serialize;

use super::baseline::vlmap_script;
use super::score::{nav_scores, reached};
use super::suite::NavTask;
use agent::Tuple;
use planner_dsl::typed::TypedPlan;

/// The noise kinds a rate may apply to (`--kinds`).
pub const NOISE_KINDS: [&str; 5] = ["label_flip", "fragment", "merge", "drop", "colour_shift"];

/// What to run.
#[derive(Debug, Clone, PartialEq)]
pub struct NoiseStudyOptions {
    /// Noise rates, each applied to every kind in `kinds`.
    pub rates: Vec<f64>,
    /// First seed; seeds `seed .. seed + seeds` are averaged.
    pub seed: u64,
    /// How many seeds are averaged.
    pub seeds: usize,
    /// Kinds the rate applies to (names of [`NOISE_KINDS`]); the others stay at 0.
    pub kinds: Vec<String>,
}

impl Default for NoiseStudyOptions {
    fn default() -> Self {
        NoiseStudyOptions {
            rates: vec![0.0, 0.05, 0.1, 0.2, 0.3],
            seed: 0,
            seeds: 5,
            kinds: NOISE_KINDS.iter().map(|k| (*k).to_string()).collect(),
        }
    }
}

/// Averaged figures of one method at one rate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NoiseRow {
    /// The noise rate.
    pub rate: f64,
    /// "ivlmap" (reference plans) or "vlmap" (the baseline).
    pub method: String,
    /// Mean over seeds of T_1..T_K.
    #[serde(rename = "T")]
    pub t: Vec<f64>,
    /// Mean over seeds of SR.
    #[serde(rename = "SR")]
    pub sr: f64,
    /// Per seed: T_1..T_K then SR.
    pub per_seed: Vec<Vec<f64>>,
}

/// What the noise did to the maps at one rate (means per map over seeds and scenes).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NoiseEffects {
    /// The noise rate.
    pub rate: f64,
    /// Objects in the scenes (per map).
    pub objects: f64,
    /// Instances in the built maps.
    pub instances: f64,
    /// Objects whose mask was dropped, per map.
    pub dropped: f64,
    /// Masks merged into a neighbour, per map.
    pub merged: f64,
    /// Objects whose mask was split into fragments, per map.
    pub fragmented: f64,
    /// Objects whose colour evidence was shifted, per map.
    pub colour_shifted: f64,
    /// Instances whose colour word differs from the object they sit on (their
    /// centroid's true instance), per map.
    pub wrong_colour: f64,
    /// Instances whose category differs from that object's, per map.
    pub wrong_label: f64,
}

/// The whole study (the `--report` JSON).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NoiseStudy {
    /// The suite files (names) the tasks came from.
    pub suites: Vec<String>,
    /// How many tasks were run per rate, seed and method.
    pub tasks: usize,
    /// The noise kinds the rates applied to.
    pub kinds: Vec<String>,
    /// The seeds averaged.
    pub seeds: Vec<u64>,
    /// Figures per rate and method.
    pub rows: Vec<NoiseRow>,
    /// What the noise did to the maps, per rate.
    pub effects: Vec<NoiseEffects>,
}

/// The VLMaps tuples of a reference plan: each selection's category and each bare
/// name (a region or category) a step goes to, in source order; ordinals, colours and
/// orders are dropped.
///
/// # Errors
/// The parse error (with its position) when the plan is not a straight-line plan.
pub fn reference_tuples(src: &str) -> Result<Vec<Tuple>, String> {
    let plan = TypedPlan::parse(src).map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    for step in &plan.steps {
        for t in step.targets() {
            out.push(Tuple::new(&t.name, None, None));
        }
        for n in step.names() {
            out.push(Tuple::new(n, None, None));
        }
    }
    Ok(out)
}

/// The two plans of a task: ivlmap (reference) and vlmap (nearest of each category).
fn plans(task: &NavTask) -> Result<[Plan; 2], String> {
    let src = task.reference.as_deref().ok_or_else(|| {
        format!(
            "task {} (line {}) has no \"reference\" plan",
            task.id, task.line
        )
    })?;
    let at = |e: String| format!("task {} (line {}): reference plan: {e}", task.id, task.line);
    let ivl = Plan::compile(src).map_err(|e| at(e.to_string()))?;
    let tuples = reference_tuples(src).map_err(at)?;
    let vl = Plan::compile(&vlmap_script(&tuples)).map_err(|e| at(e.to_string()))?;
    Ok([ivl, vl])
}

/// FNV-1a of a name: a per-scene seed offset that does not depend on the Rust
/// version (std's hasher is not guaranteed stable).
fn fnv1a(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

fn noise_for(rate: f64, seed: u64, kinds: &[String]) -> PerceptionNoise {
    let mut n = PerceptionNoise::none(seed);
    for k in kinds {
        match k.as_str() {
            "label_flip" => n.label_flip = rate,
            "fragment" => n.fragment = rate,
            "merge" => n.merge = rate,
            "drop" => n.drop = rate,
            "colour_shift" => n.colour_shift = rate,
            _ => {}
        }
    }
    n
}

/// Label and colour errors of a built map: each instance against the true instance
/// under its centroid (none there: not counted).
fn wrong_attributes(built: &IvlMap, truth: &IvlMap) -> (usize, usize) {
    let (mut colour, mut label) = (0, 0);
    for i in &built.instances {
        if let Some(t) = truth.instance_at(i.centroid) {
            colour += usize::from(t.colour != i.colour);
            label += usize::from(t.label != i.label);
        }
    }
    (colour, label)
}

/// Runs the study over `tasks` (from one or more suites).
///
/// # Errors
/// A message naming the task or scene file when a reference plan is missing or does
/// not compile, a scene cannot be read, or a rate or kind is invalid.
pub fn noise_study(
    suites: &[String],
    tasks: &[NavTask],
    opts: &NoiseStudyOptions,
    on_step: &mut dyn FnMut(&str),
) -> Result<NoiseStudy, String> {
    for k in &opts.kinds {
        if !NOISE_KINDS.contains(&k.as_str()) {
            return Err(format!(
                "unknown noise kind {k:?}; the kinds are {}",
                NOISE_KINDS.join(", ")
            ));
        }
    }
    if let Some(r) = opts.rates.iter().find(|r| !(0.0..=1.0).contains(*r)) {
        return Err(format!("noise rate {r} is not in [0, 1]"));
    }
    if opts.seeds == 0 {
        return Err("--seeds must be at least 1".into());
    }
    let plans: Vec<[Plan; 2]> = tasks.iter().map(plans).collect::<Result<_, _>>()?;
    // Scenes, once each, in first-use order.
    let mut scenes: BTreeMap<PathBuf, (Scene, Arc<IvlMap>)> = BTreeMap::new();
    for t in tasks {
        if !scenes.contains_key(&t.scene_path) {
            let s = Scene::from_path(&t.scene_path).map_err(|e| e.to_string())?;
            scenes.insert(t.scene_path.clone(), (s, t.map.clone()));
        }
    }
    let clean: BTreeMap<&PathBuf, PerceptionInputs> = scenes
        .iter()
        .map(|(p, (s, _))| (p, PerceptionInputs::from_scene(s)))
        .collect();
    let seeds: Vec<u64> = (0..opts.seeds as u64).map(|k| opts.seed + k).collect();
    let limits = Limits::default();
    let mut rows = Vec::new();
    let mut effects = Vec::new();
    for &rate in &opts.rates {
        let mut per_seed: [Vec<Vec<f64>>; 2] = [Vec::new(), Vec::new()];
        let mut eff = NoiseEffects {
            rate,
            objects: 0.0,
            instances: 0.0,
            dropped: 0.0,
            merged: 0.0,
            fragmented: 0.0,
            colour_shifted: 0.0,
            wrong_colour: 0.0,
            wrong_label: 0.0,
        };
        let mut n_maps = 0usize;
        for &seed in &seeds {
            on_step(&format!("rate {rate} seed {seed}"));
            // One noisy map (and planner) per scene.
            let mut maps: BTreeMap<&PathBuf, (Arc<IvlMap>, Arc<GridPlanner>, Arc<_>)> =
                BTreeMap::new();
            for (path, inputs) in &clean {
                let name = path.display().to_string();
                // the scene's own name, not its path: the same draws from any folder
                let noise = noise_for(rate, seed ^ fnv1a(&scenes[*path].0.name), &opts.kinds);
                let (noisy, log): (PerceptionInputs, NoiseLog) = inputs
                    .with_noise(&noise)
                    .map_err(|e| format!("{name}: {e}"))?;
                let built = build_map(&noisy, &BuildConfig::default())
                    .map_err(|e| format!("{name}: {e}"))?;
                let truth = &scenes[*path].1;
                let (wc, wl) = wrong_attributes(&built.map, truth);
                eff.objects += truth.instances.len() as f64;
                eff.instances += built.map.instances.len() as f64;
                eff.dropped += log.dropped.len() as f64;
                eff.merged += log.merged.len() as f64;
                eff.fragmented += log.fragmented.len() as f64;
                eff.colour_shifted += log.colour_shifted.len() as f64;
                eff.wrong_colour += wc as f64;
                eff.wrong_label += wl as f64;
                n_maps += 1;
                let map = Arc::new(built.map);
                let inflated = Arc::new(inflate_m(
                    &map.obstacles,
                    map.robot_radius,
                    map.frame.cell_size,
                ));
                let planner = Arc::new(GridPlanner::new((*inflated).clone()));
                maps.insert(path, (map, planner, inflated));
            }
            for (m, out) in per_seed.iter_mut().enumerate() {
                let reached_all: Vec<Vec<bool>> = tasks
                    .iter()
                    .zip(&plans)
                    .map(|(task, p)| {
                        let (map, planner, inflated) = &maps[&task.scene_path];
                        let mut robot = SimRobot::from_parts(
                            map.clone(),
                            planner.clone(),
                            inflated.clone(),
                            task.start,
                        );
                        let _ = planner_dsl::run(&p[m], map, &mut robot, &limits);
                        reached(&task.map, &task.subgoals, &robot.trajectory().stops)
                    })
                    .collect();
                let s = nav_scores(&reached_all);
                let mut v = s.t.clone();
                v.push(s.sr);
                out.push(v);
            }
        }
        let k = n_maps.max(1) as f64;
        for f in [
            &mut eff.objects,
            &mut eff.instances,
            &mut eff.dropped,
            &mut eff.merged,
            &mut eff.fragmented,
            &mut eff.colour_shifted,
            &mut eff.wrong_colour,
            &mut eff.wrong_label,
        ] {
            *f /= k;
        }
        effects.push(eff);
        for (m, name) in ["ivlmap", "vlmap"].iter().enumerate() {
            let runs = &per_seed[m];
            let width = runs.iter().map(Vec::len).max().unwrap_or(0);
            let mean: Vec<f64> = (0..width)
                .map(|j| {
                    runs.iter().filter_map(|r| r.get(j)).sum::<f64>() / runs.len().max(1) as f64
                })
                .collect();
            let (t, sr) = match mean.split_last() {
                Some((sr, t)) => (t.to_vec(), *sr),
                None => (Vec::new(), 0.0),
            };
            rows.push(NoiseRow {
                rate,
                method: (*name).to_string(),
                t,
                sr,
                per_seed: runs.clone(),
            });
        }
    }
    Ok(NoiseStudy {
        suites: suites.to_vec(),
        tasks: tasks.len(),
        kinds: opts.kinds.clone(),
        seeds,
        rows,
        effects,
    })
}

/// The table printed by `ivlmap noise-study`: per rate, T_1..T_4 and SR of ivlmap
/// and vlmap (means over seeds), then what the noise did to the maps.
#[must_use]
pub fn noise_table(study: &NoiseStudy) -> String {
    let mut s = String::new();
    let k = study.rows.iter().map(|r| r.t.len()).max().unwrap_or(0);
    let _ = writeln!(
        s,
        "noise study: {} ({} tasks), kinds {}, seeds {:?}",
        study.suites.join(", "),
        study.tasks,
        study.kinds.join("+"),
        study.seeds
    );
    let head: Vec<String> = (1..=k).map(|i| format!("T{i}")).collect();
    let cols = |m: &str| {
        head.iter()
            .map(|h| format!("{m} {h}"))
            .chain(std::iter::once(format!("{m} SR")))
            .collect::<Vec<_>>()
    };
    let mut header = vec!["rate".to_string()];
    header.extend(cols("ivlmap"));
    header.extend(cols("vlmap"));
    let _ = writeln!(s, "| {} |", header.join(" | "));
    let _ = writeln!(s, "|{}", "---|".repeat(header.len()));
    let mut by_rate: Vec<(f64, Vec<&NoiseRow>)> = Vec::new();
    for r in &study.rows {
        match by_rate.iter_mut().find(|(x, _)| *x == r.rate) {
            Some((_, v)) => v.push(r),
            None => by_rate.push((r.rate, vec![r])),
        }
    }
    for (rate, rs) in &by_rate {
        let mut cells = vec![format!("{rate}")];
        for m in ["ivlmap", "vlmap"] {
            if let Some(r) = rs.iter().find(|r| r.method == m) {
                cells.extend((0..k).map(|i| r.t.get(i).map_or("-".into(), |v| format!("{v:.3}"))));
                cells.push(format!("{:.3}", r.sr));
            }
        }
        let _ = writeln!(s, "| {} |", cells.join(" | "));
    }
    let _ = writeln!(
        s,
        "\nper map (mean): objects, instances built, masks dropped/merged/fragmented, objects colour-shifted, instances with a wrong colour / category"
    );
    for e in &study.effects {
        let _ = writeln!(
            s,
            "  rate {}: {:.1} objects, {:.1} instances, {:.1}/{:.1}/{:.1}, {:.1} shifted, {:.1} wrong colour, {:.1} wrong category",
            e.rate,
            e.objects,
            e.instances,
            e.dropped,
            e.merged,
            e.fragmented,
            e.colour_shifted,
            e.wrong_colour,
            e.wrong_label
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_tuples_keep_names_in_order_and_drop_attributes() {
        let src = "agent.move_to_object(agent.get_obj_attributes(\"table\", 2, \"yellow\", \"west_to_east\"));\n\
                   agent.move_in_between(agent.get_obj_attributes(\"table\", 0, \"black\"), agent.get_obj_attributes(\"sofa\", 0, \"red\"));\n\
                   agent.move_to_object(\"kitchen\");";
        let t = reference_tuples(src).unwrap();
        let names: Vec<&str> = t.iter().map(|t| t.object.as_str()).collect();
        assert_eq!(names, ["table", "table", "sofa", "kitchen"]);
        assert!(t.iter().all(|t| t.ordinal.is_none() && t.colour.is_none()));
        assert!(reference_tuples("agent.move_to_object(").is_err());
    }
}
