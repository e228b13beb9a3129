//! The command line: clap's derive types for every subcommand and the backend flags.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use agent::PlanOptions;

use crate::backend::BackendChoice;

#[derive(Debug, Parser)]
#[command(
    name = "ivlmap",
    version,
    about = "Language to robot plans on an instance-level semantic map (IVLMap)"
)]
pub(crate) struct Cli {
    /// More log output on stderr (-v info, -vv debug, -vvv trace); RUST_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    pub(crate) verbose: u8,
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Debug, Subcommand)]
pub(crate) enum Command {
    /// Chat with the robot: each instruction is planned, shown and executed.
    Chat {
        /// Scene file (.scene.json) or saved map folder.
        #[arg(long)]
        scene: PathBuf,
        #[command(flatten)]
        backend: BackendArgs,
        /// Prompt folder (a variant overlaying the built-in templates).
        #[arg(long)]
        prompts: Option<PathBuf>,
        #[command(flatten)]
        robot: crate::robot::RobotArgs,
    },
    /// Run a mission unattended: a .rhai plan or a list of instructions (one per line, # comments).
    Run {
        /// The mission file.
        mission: PathBuf,
        /// Scene file or map folder (default: the mission's `scene:` header comment).
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Write the trajectory JSON here (also when the mission fails part-way).
        #[arg(long)]
        trajectory: Option<PathBuf>,
        /// Draw the map with the trajectory to this PNG.
        #[arg(long)]
        png: Option<PathBuf>,
        #[command(flatten)]
        backend: BackendArgs,
        /// Prompt folder (a variant overlaying the built-in templates).
        #[arg(long)]
        prompts: Option<PathBuf>,
        #[command(flatten)]
        robot: crate::robot::RobotArgs,
    },
    /// Show the tuples and the script for an instruction; run nothing.
    Plan {
        /// The instruction.
        instruction: String,
        /// Scene file or map folder.
        #[arg(long)]
        scene: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        backend: BackendArgs,
        /// Prompt folder (a variant overlaying the built-in templates).
        #[arg(long)]
        prompts: Option<PathBuf>,
    },
    /// Evaluate an extraction (.extract.jsonl) or navigation (.nav.jsonl) suite.
    Eval {
        /// The suite file.
        suite: PathBuf,
        /// Backend(s); several give a side-by-side table.
        #[arg(long = "backend", value_name = "B", default_value = "llama")]
        backends: Vec<String>,
        #[command(flatten)]
        model_args: ModelArgs,
        /// Prompt variant folder(s); several give a side-by-side table (default: built-in).
        #[arg(long = "prompts", value_name = "DIR")]
        prompts: Vec<PathBuf>,
        /// Write the report JSON here (with several runs: FILE's stem plus the run's label).
        #[arg(long)]
        report: PathBuf,
        /// Navigation: run a baseline instead of ivlmap (vlmap: nearest instance of each
        /// category, as VLMaps; reference: each task's hand-written plan, no model).
        #[arg(long, value_enum)]
        baseline: Option<Baseline>,
    },
    /// Serve the web chat (a page with the live map) and the HTTP API on one address.
    Serve(Box<ServeArgs>),
    /// Map tools: inspect, render, save.
    Map {
        #[command(subcommand)]
        command: MapCommand,
    },
    /// Navigation under simulated perception noise: reference plans (ivlmap) and the
    /// VLMaps baseline on maps built from corrupted perception, scored on the true scene.
    NoiseStudy(crate::noise_cmd::NoiseStudyArgs),
}

/// `ivlmap serve`.
#[derive(Debug, Args)]
pub(crate) struct ServeArgs {
    /// Scene file (.scene.json).
    #[arg(long, required_unless_present = "map", conflicts_with = "map")]
    pub(crate) scene: Option<PathBuf>,
    /// A map folder saved by `ivlmap map save`.
    #[arg(long)]
    pub(crate) map: Option<PathBuf>,
    /// Address to listen on; anything but loopback needs --token.
    #[arg(long, default_value = server::config::DEFAULT_ADDR)]
    pub(crate) addr: String,
    /// Every /api request must send `Authorization: Bearer T` (the page asks for it).
    #[arg(long, env = "IVLMAP_TOKEN", hide_env_values = true)]
    pub(crate) token: Option<String>,
    /// Instructions planned at once (default: 1 for llama, which answers one at a
    /// time, 4 for other backends).
    #[arg(long)]
    pub(crate) workers: Option<usize>,
    /// Sessions idle this many minutes expire.
    #[arg(long, default_value_t = 30)]
    pub(crate) session_minutes: u64,
    /// Most sessions at once.
    #[arg(long, default_value_t = 256)]
    pub(crate) max_sessions: usize,
    #[command(flatten)]
    pub(crate) backend: BackendArgs,
    /// Prompt folder (a variant overlaying the built-in templates).
    #[arg(long)]
    pub(crate) prompts: Option<PathBuf>,
    /// The robot plans run on: `sim` gives every session its own simulator; `nav2` is
    /// one real robot that one session drives at a time (others preview, and are
    /// refused with 409 `robot_busy` when they ask it to move).
    #[command(flatten)]
    pub(crate) robot: crate::robot::RobotArgs,
}

#[derive(Debug, Subcommand)]
pub(crate) enum MapCommand {
    /// Print the instance table (id, label, k/n, colour, area, centroid) and regions.
    Inspect {
        /// Scene file or saved map folder.
        map: PathBuf,
    },
    /// Draw the map (optionally with a trajectory) to a PNG.
    Render {
        /// Scene file or saved map folder.
        map: PathBuf,
        /// The PNG to write.
        #[arg(long)]
        out: PathBuf,
        /// A trajectory JSON (from `ivlmap run --trajectory`) to draw on top.
        #[arg(long)]
        trajectory: Option<PathBuf>,
    },
    /// Rasterise a scene and save the map folder (map.json, instances.json, .npy layers).
    Save {
        /// Scene file.
        scene: PathBuf,
        /// The folder to write.
        #[arg(long)]
        out: PathBuf,
    },
    /// Build a map folder from perception outputs (SAM masks + label map), an RGB-D
    /// dataset or a VLMaps map, and print what was kept and dropped.
    Build(Box<crate::mapbuild::MapBuildArgs>),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Baseline {
    /// VLMaps: the nearest instance of each mentioned category (no ordinals, no colours).
    Vlmap,
    /// The suite's hand-written reference plans (no model).
    Reference,
}

#[derive(Debug, Args)]
pub(crate) struct BackendArgs {
    /// LLM backend: llama (local GGUF), openai (OpenAI-compatible server), replay (cassette).
    #[arg(long, default_value = "llama")]
    pub(crate) backend: String,
    #[command(flatten)]
    pub(crate) model_args: ModelArgs,
}

impl BackendArgs {
    pub(crate) fn choice(&self) -> BackendChoice {
        self.model_args.choice(&self.backend)
    }
}

/// When llama.cpp uses its flash attention kernel (`--flash-attention`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum FlashAttention {
    On,
    Off,
    /// llama.cpp's own choice (on where the device supports it, a CPU included).
    Auto,
}

/// A sampling temperature: a finite number above 0.
fn temperature(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(t) if t.is_finite() && t > 0.0 => Ok(t),
        _ => Err(format!("`{s}` is not a temperature above 0 (e.g. 0.7)")),
    }
}

/// Backend settings shared by every command that talks to a model.
#[derive(Debug, Args)]
pub(crate) struct ModelArgs {
    /// llama: GGUF file (default ~/.cache/ivlmap/models/qwen2.5-coder-1.5b-instruct-q4_k_m.gguf,
    /// IVLMAP_MODELS overrides the folder); openai: model id.
    #[arg(long)]
    pub(crate) model: Option<String>,
    /// openai: server base URL (else IVLMAP_BASE_URL; key from IVLMAP_API_KEY).
    #[arg(long)]
    pub(crate) base_url: Option<String>,
    /// replay: the cassette to answer from.
    #[arg(long)]
    pub(crate) cassette: Option<PathBuf>,
    /// Record every request and answer to this cassette.
    #[arg(long)]
    pub(crate) record: Option<PathBuf>,
    /// llama: CPU threads.
    #[arg(long)]
    pub(crate) threads: Option<u32>,
    /// llama: llama.cpp's flash attention kernel (default auto: llama.cpp's choice, on for
    /// a CPU). Off generates about 1.2x faster after a long cached prompt, but a greedy
    /// answer may then depend on what the prompt cache held.
    #[arg(long, value_enum, value_name = "WHEN", default_value = "auto")]
    pub(crate) flash_attention: FlashAttention,
    /// llama: folder of the prompt cache on disk (snapshots of long prompt prefixes read
    /// back by later runs; default ~/.cache/ivlmap/prompt-cache).
    #[arg(long, conflicts_with = "no_prompt_cache")]
    pub(crate) prompt_cache: Option<PathBuf>,
    /// llama: no prompt cache on disk (every run evaluates its prompts from scratch).
    #[arg(long)]
    pub(crate) no_prompt_cache: bool,
    /// Decode without the answer's grammar (llama; openai only with --send-grammar):
    /// measures the model alone.
    #[arg(long)]
    pub(crate) no_grammar: bool,
    /// openai: send the answer's grammar to the server as GBNF in the request's
    /// `grammar` field (llama-server takes it; most other servers do not).
    #[arg(long)]
    pub(crate) send_grammar: bool,
    /// Show the K worked examples most similar to each instruction (ranked by MiniLM)
    /// instead of all of them in the cached prefix.
    #[arg(long, value_name = "K")]
    pub(crate) examples: Option<usize>,
    /// llama: hold the answer with llama.cpp's GBNF sampler instead of llguidance
    /// (slower; for comparison).
    #[arg(long)]
    pub(crate) gbnf: bool,
    /// Offer every count and order in the plan's selections, not only those the
    /// instruction says (for comparison; the checks then re-ask).
    #[arg(long)]
    pub(crate) open_selections: bool,
    /// Narrow each pick's colours to those the person said that an object of that name
    /// has on the map, outside a conversation. The default since stop 72; the flag is
    /// kept so that earlier commands still run.
    #[arg(long, conflicts_with_all = ["open_selections", "unsaid_colours_allowed"])]
    pub(crate) said_colours: bool,
    /// Let a pick select on any colour its objects have on the map, said or not (the
    /// default before stop 72; for comparison; the checks then re-ask an unsaid one).
    #[arg(long)]
    pub(crate) unsaid_colours_allowed: bool,
    /// Let a pick exclude any colour its objects tell apart by (`not_colour`), not only
    /// a colour the person said where a word excludes something (the default before
    /// stop 63; for comparison).
    #[arg(long)]
    pub(crate) any_not_colours: bool,
    /// Let a pick of any object count in a directional order wherever the instruction
    /// names a direction, not only one whose clause names it (the default before stop
    /// 64; for comparison).
    #[arg(long)]
    pub(crate) directions_anywhere: bool,
    /// Let a pick select in a room (`region:`) only where the instruction says that room
    /// of its object, in the clause naming it or one next to it naming no object. The
    /// default since stop 81; the flag is kept so that earlier commands still run.
    #[arg(long, conflicts_with = "regions_anywhere")]
    pub(crate) regions_of_said: bool,
    /// Let a pick select in any room the instruction names, said of it or not (the
    /// default before stop 81; for comparison; the checks then re-ask an unsaid one).
    #[arg(long)]
    pub(crate) regions_anywhere: bool,
    /// Let a pick name any object of the map, named in the instruction or not (the
    /// default before stop 82; for comparison; the checks then re-ask a pick of an
    /// object nobody named).
    #[arg(long)]
    pub(crate) names_anywhere: bool,
    /// Let a plan end anywhere where the instruction names a room last, alone in its
    /// clause (the default before stop 82; for comparison; the checks then re-ask a
    /// plan that never goes into it).
    #[arg(long)]
    pub(crate) last_room_free: bool,
    /// Let a pick of any object count two or more wherever the instruction says such a
    /// count, not only one whose clause says it (the default before stop 64; for
    /// comparison).
    #[arg(long)]
    pub(crate) counts_anywhere: bool,
    /// Let `move_between_the_two` name any object with two or more on the map, not only
    /// one the person said in the plural (the default before stop 66; for comparison).
    #[arg(long)]
    pub(crate) pairs_anywhere: bool,
    /// Bar from the plan's stops, and from `move_in_between`, an object the person asks
    /// to stop between two of ("between the two red ball racks", named nowhere else):
    /// only `move_between_the_two` may name it (off by default: measured worse on the
    /// dev sets at stop 74).
    #[arg(long)]
    pub(crate) pair_stops_barred: bool,
    /// Let a pick count in any directional order wherever the instruction names a
    /// direction, not only the orders its words count in ("the second to last seat from
    /// the west" in `east_to_west`; the default before stop 67; for comparison).
    #[arg(long)]
    pub(crate) any_direction: bool,
    /// Let a pick count from the far end (`far_to_near`) wherever the instruction speaks
    /// of a far end, not only where it does of that object (the default before stop 68;
    /// for comparison).
    #[arg(long)]
    pub(crate) far_end_anywhere: bool,
    /// Bar `move_to_object` from an object the person named only as a side stop ("stop
    /// on the north side of the red sofa") in the first answer, not only in the re-ask
    /// after a missing side move (off by default: measured worse on held-out v9, dev).
    #[arg(long)]
    pub(crate) side_stops_barred: bool,
    /// Leave the plan's first step free where the first thing the person names is a
    /// side stop ("stop on the north side of the white desk, then ..."); by default
    /// (since stop 73) it must be that side move of that object. For comparison: the
    /// checks then re-ask a plain stop there.
    #[arg(long)]
    pub(crate) first_side_free: bool,
    /// Let the re-ask write its whole answer again, not only from the first step a
    /// finding disputes (the default before stop 69; for comparison).
    #[arg(long)]
    pub(crate) reask_whole: bool,
    /// Let a pick be picked near any object, not only one the person named in a clause
    /// with it (the default before stop 67; for comparison).
    #[arg(long)]
    pub(crate) anchors_anywhere: bool,
    /// Let a pick take a colour the person said only of other objects (the default
    /// before stop 70; for comparison).
    #[arg(long)]
    pub(crate) colours_of_others_allowed: bool,
    /// Let the re-ask drop the move back to the start that the first answer made (the
    /// default before stop 71; for comparison).
    #[arg(long)]
    pub(crate) reask_may_drop_return: bool,
    /// Let the re-ask's answer end before the first answer's later steps that no finding
    /// disputes (the default before stop 75; for comparison).
    #[arg(long)]
    pub(crate) reask_may_shorten: bool,
    /// Take an extraction case's first objects line as it is, with no re-ask for a place
    /// the person put an object in that it lists no word of, for a name it lists less a
    /// word the person said, nor for a direction the person counted in that it lists no
    /// order of (the default before stop 75; for comparison).
    #[arg(long)]
    pub(crate) no_extraction_reask: bool,
    /// Let a re-ask that keeps the steps before a stop the plan lacks write that stop
    /// anywhere after them, not first (the default before stop 76; for comparison).
    #[arg(long)]
    pub(crate) reask_stop_anywhere: bool,
    /// Let an object on the objects line of an extraction case be made of any word, not
    /// only the person's words and their singulars (the default before stop 75; for
    /// comparison).
    #[arg(long)]
    pub(crate) any_object_words: bool,
    /// Let a tuple on the objects line carry any colour word, not only a colour the
    /// person said (the default before stop 51; for comparison).
    #[arg(long)]
    pub(crate) any_tuple_colours: bool,
    /// Let a pick select on any colour of the map, not only one its objects have, and
    /// `move_between_the_two` name any object on any colour, not only a pair's (the
    /// defaults before stops 52 and 53; for comparison).
    #[arg(long)]
    pub(crate) any_pick_colours: bool,
    /// After the re-ask still disagrees with the checks, draw up to N more answers
    /// (sampled, seeds 1..N) before asking the person; the first the checks accept is
    /// the plan.
    #[arg(long, value_name = "N", default_value_t = PlanOptions::default().redraws)]
    pub(crate) redraws: u32,
    /// The temperature of those draws.
    #[arg(
        long,
        value_name = "T",
        default_value_t = PlanOptions::default().redraw_temperature,
        value_parser = temperature
    )]
    pub(crate) redraw_temperature: f32,
    /// After the re-ask, draw no greedy answer with the worked examples in reverse order
    /// (for comparison).
    #[arg(long)]
    pub(crate) no_reversed_draw: bool,
    /// Write each answer in two requests, the objects line, then the plan under a grammar
    /// that line narrows where the person's words agree with it (a pick of a name whose
    /// every tuple gives a colour said before that name selects on one of them, kept or
    /// excluded). Off by default until judged on the untuned sets.
    #[arg(long)]
    pub(crate) follow_objects: bool,
    /// From the first answer on, a pick of a name said only with a colour right before it
    /// ("the yellow table closest to the counter") selects on a colour said of it.
    #[arg(long)]
    pub(crate) said_colours_required: bool,
}

impl ModelArgs {
    pub(crate) fn choice(&self, backend: &str) -> BackendChoice {
        BackendChoice {
            name: backend.to_string(),
            model: self.model.clone(),
            base_url: self.base_url.clone(),
            cassette: self.cassette.clone(),
            record: self.record.clone(),
            threads: self.threads,
            flash_attention: match self.flash_attention {
                FlashAttention::On => Some(true),
                FlashAttention::Off => Some(false),
                FlashAttention::Auto => None,
            },
            send_grammar: self.send_grammar,
            prompt_cache: if self.no_prompt_cache {
                None
            } else {
                self.prompt_cache
                    .clone()
                    .or_else(crate::backend::default_prompt_cache_dir)
            },
        }
    }

    pub(crate) fn plan_options(&self) -> PlanOptions {
        PlanOptions {
            examples: self.examples,
            llguidance: !self.gbnf,
            answer_grammar: !self.no_grammar,
            said_only: !self.open_selections,
            said_colours: self.said_colours || !self.unsaid_colours_allowed,
            said_exclusions: !self.any_not_colours,
            directions_of_said: !self.directions_anywhere,
            regions_of_said: self.regions_of_said || !self.regions_anywhere,
            names_of_said: !self.names_anywhere,
            last_room_stop: !self.last_room_free,
            counts_of_said: !self.counts_anywhere,
            far_ends_of_said: !self.far_end_anywhere,
            side_stops_of_said: self.side_stops_barred,
            first_side_stop: !self.first_side_free,
            reask_holds_agreed: !self.reask_whole,
            pairs_of_said: !self.pairs_anywhere,
            pair_stops_barred: self.pair_stops_barred,
            orders_of_said: !self.any_direction,
            said_object_words: !self.any_object_words,
            extraction_reask: !self.no_extraction_reask,
            reask_stops_first: !self.reask_stop_anywhere,
            reask_keeps_steps: !self.reask_may_shorten,
            anchors_of_said: !self.anchors_anywhere,
            colours_of_others: !self.colours_of_others_allowed,
            reask_keeps_return: !self.reask_may_drop_return,
            said_tuple_colours: !self.any_tuple_colours,
            map_colours: !self.any_pick_colours,
            redraws: self.redraws,
            redraw_temperature: self.redraw_temperature,
            reversed_draw: !self.no_reversed_draw,
            follow_objects: self.follow_objects,
            said_colours_required: self.said_colours_required,
            ..PlanOptions::default()
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_redraw_temperature_is_a_finite_number_above_zero() {
        assert_eq!(super::temperature("0.7"), Ok(0.7));
        for bad in ["0", "-1", "nan", "inf", "warm"] {
            let e = super::temperature(bad).unwrap_err();
            assert!(e.contains(bad), "{e}");
        }
    }
}
