//! What the language layer takes and gives: [`PlanContext`] and [`PlanOptions`] in,
//! [`Outcome`] out, [`LanguageError`] when it cannot answer; [`plan_instruction`] and
//! [`extract_tuples`] are the entry points (one constrained model call each, see
//! [`crate::v2`]).

use map_core::{IvlMap, Pose, SimRobot};
use planner_dsl::Plan;
use serde::Serialize;

use llm::{Completion, LlmBackend, LlmError};

use crate::prompts::{PromptError, Prompts};
use crate::tuples::{Tuple, TupleParseError};

/// Everything that can stop the language layer (a question or refusal is not an error: see
/// [`Outcome`]).
#[derive(Debug, thiserror::Error)]
pub enum LanguageError {
    /// A prompt template failed.
    #[error(transparent)]
    Prompt(#[from] PromptError),
    /// The backend failed.
    #[error("LLM backend: {0}")]
    Backend(#[from] LlmError),
    /// Step 1's answer holds no usable tuples.
    #[error(
        "cannot read the objects from the model's answer: {source}; the answer was {answer:?}"
    )]
    Tuples {
        /// Why.
        source: TupleParseError,
        /// The model's answer.
        answer: String,
    },
}

/// Time and tokens spent on LLM calls.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Timing {
    /// LLM requests made.
    pub llm_calls: u32,
    /// Prompt tokens over all requests.
    pub prompt_tokens: u64,
    /// Of those, reused from the KV cache.
    pub cached_prompt_tokens: u64,
    /// Generated tokens.
    pub completion_tokens: u64,
    /// Prompt processing, ms (as the backend reports).
    pub prompt_ms: f64,
    /// Generation, ms (as the backend reports).
    pub generate_ms: f64,
    /// Wall time of the whole step, ms.
    pub wall_ms: f64,
}

impl Timing {
    pub(crate) fn add(&mut self, c: &Completion) {
        self.llm_calls += 1;
        self.prompt_tokens += u64::from(c.prompt_tokens);
        self.cached_prompt_tokens += u64::from(c.cached_prompt_tokens);
        self.completion_tokens += u64::from(c.completion_tokens);
        self.prompt_ms += c.prompt_ms;
        self.generate_ms += c.generate_ms;
    }
}

/// Knobs of the language layer.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanOptions {
    /// Re-ask once, naming what the checks found, before asking the person (default on).
    pub reask: bool,
    /// Token budget of [`extract_tuples`]' objects line (default 96).
    pub extract_max_tokens: u32,
    /// Token budget of each answer (default 384).
    pub plan_max_tokens: u32,
    /// Dry-run a candidate plan on a copy of the robot (when one is given); a runtime
    /// error becomes a finding (default on).
    pub dry_run: bool,
    /// Worked examples shown per instruction: `None` (default) puts every worked example
    /// in the static prefix (right after the system message; the map's summary then
    /// opens the request), so a prefix-caching backend evaluates them once for every
    /// map and instruction; `Some(k)` shows the `k` most similar to the instruction
    /// instead (by [`crate::v2::examples`]' ranking; smaller prompts, no shared prefix).
    pub examples: Option<usize>,
    /// Hold the answer to the grammar of [`crate::v2::grammar::answer_grammar`]
    /// (backends that take GBNF; default on).
    pub answer_grammar: bool,
    /// Send the grammar in Lark too, which the llama backend runs with llguidance
    /// instead of GBNF (default on; off measures GBNF).
    pub llguidance: bool,
    /// Narrow the grammar's selections to what the person said (default on): counts
    /// the instruction says (outside a conversation; 1 and -1 always), directional
    /// orders only when it names a side or a compass direction. What those checks would
    /// re-ask, the grammar prevents; the checks stay for backends that take no grammar.
    /// Colours are narrowed only with `said_colours`.
    pub said_only: bool,
    /// With `said_only`, outside a conversation: a pick of each object may select only
    /// on the colours the person said that some object of that name has on this map
    /// (default on since stop 72; `--unsaid-colours-allowed` turns it off).
    pub said_colours: bool,
    /// With `said_only`, outside a conversation: a pick (and a pair of
    /// `move_between_the_two`) may exclude a colour (`not_colour`) only where the person
    /// excludes something, and only a colour they said (default on; `--any-not-colours`
    /// turns it off).
    pub said_exclusions: bool,
    /// With `said_only`, outside a conversation: a pick may count in a directional order
    /// only where the person said a direction of its object, in the clause naming it
    /// (default on; `--directions-anywhere` turns it off).
    pub directions_of_said: bool,
    /// With `said_only`, outside a conversation: a pick may select in a region
    /// (`region:`) only where the person said that region of its object, in the clause
    /// naming it or a clause next to it that names no object, and `assess` finds such a
    /// pick from a backend without grammars (default on since stop 81, judged on the dev
    /// sets' 31 tasks that had a room in a plan: 28/31 against 24/31;
    /// `--regions-anywhere` turns it off).
    pub regions_of_said: bool,
    /// With `said_only`, outside a conversation: a pick (`get_obj`, a `near:` anchor, a
    /// pair) may name only the objects the instruction names (a name, a synonym, a typo
    /// of one: what `check_unnamed_stops` accepts), where it names any (default on since
    /// stop 82; `--names-anywhere` turns it off).
    pub names_of_said: bool,
    /// With `said_only`, outside a conversation: where the last thing the instruction
    /// names is a room, alone in its clause ("..., and wrap up in the medic hut"), the
    /// plan's last statement is the move into it, unless a move back is asked for
    /// (default on since stop 82; `--last-room-free` turns it off). Measured at stop 82
    /// on the 17 tasks of held-out v17 (dev) that failed or were re-asked in its third
    /// run: 10/17 with it (and the stop's other changes) against 7/17, none lost; four
    /// first answers that had left the room out were right without a re-ask. A first
    /// answer that loops (the same stop again and again) then runs to its token limit
    /// before the room (wb02, lost either way): a cap on the statements is next.
    pub last_room_stop: bool,
    /// With `said_only`, outside a conversation: a pick may count two or more (either
    /// end) only where the person said a count of its object, in the clause naming it
    /// (default on; `--counts-anywhere` turns it off).
    pub counts_of_said: bool,
    /// With `said_only`, outside a conversation: a pick may count in `far_to_near` only
    /// where the person spoke of the far end of its object, in the clause naming it
    /// (default on; `--far-end-anywhere` turns it off).
    pub far_ends_of_said: bool,
    /// With `said_only`, outside a conversation: `move_to_object` (and a `let`) may not
    /// take an object the person named once, as a stop at one of its sides ("stop on
    /// the north side of the red sofa": `check::sides_said_of_once`). Default off
    /// (`--side-stops-barred` turns it on): measured on held-out v9 (dev, stop 68), the
    /// default model that began `move_to_object(` meaning that object went on with
    /// another and lost a task (hw06) that the check and its re-ask alone kept.
    pub side_stops_of_said: bool,
    /// With `said_only`, outside a conversation: where the first thing the person names
    /// is a side stop ("Plant yourself on the north side of the white dispatch desk.
    /// Then ..."), the plan's first step must be that side move of that object
    /// (`check::side_said_first`; default on since stop 73, `--first-side-free` turns it
    /// off). Measured on held-out v10 and v11 (dev, stop 73): their 12 such tasks went
    /// from 6 to 11 right.
    pub first_side_stop: bool,
    /// With `said_only`, outside a conversation: `move_between_the_two` may name only
    /// an object the person said in the plural ("between the two red stools"; default
    /// on; `--pairs-anywhere` turns it off).
    pub pairs_of_said: bool,
    /// With `said_only`, outside a conversation: an object the person asks to stop
    /// between two of, and names nowhere else ("the gap between the two pink party
    /// tables": `check::pairs_said_between`), may be no stop of the plan's but
    /// `move_between_the_two`'s. Default off (`--pair-stops-barred` turns it on):
    /// measured at stop 74 on the 29 dev tasks that say "between the two", the default
    /// model that began `move_in_between(` then took other objects, and two tasks right
    /// before were lost (lc05, mc05); none was gained.
    pub pair_stops_barred: bool,
    /// With `said_only`: a pick may count only in the directional orders the person's
    /// words count in (`check::directions_said`: "the second to last seat from the
    /// west" in `east_to_west`, "the westernmost shelf" in `west_to_east`), where every
    /// word naming a direction is read so (default on; `--any-direction` turns it off).
    pub orders_of_said: bool,
    /// With no map (extraction), an object on the objects line is made of the person's
    /// own words and their singulars ([`crate::v2::grammar::Vocabulary::object_words`]).
    /// Off: any word (the default before stop 75; for comparison).
    pub said_object_words: bool,
    /// With no map (extraction): where the person puts an object in a place ("the till in
    /// the snack bar") that no tuple of the answer lists (`check::places_unlisted`), or
    /// where a tuple lists a name less a word the person said ("the third waiting bench"
    /// as `bench`, `check::names_cut`), or where the person counts in a direction no
    /// tuple's order counts in ("the farthest-east front loader" with no order,
    /// `check::orders_unlisted`), one re-ask naming the words. Its grammar holds the
    /// first of them (a tuple that begins with the place's word, the name whole, a count
    /// in the order) and keeps every tuple no finding is about as the first answer
    /// wrote it (`grammar::Vocabulary::held_lines`). Default on (`--no-extraction-reask`
    /// turns it off).
    pub extraction_reask: bool,
    /// A re-ask that keeps the steps before a stop the plan lacks, said alone in its
    /// clause ("then the black radar screen"), has the continuation begin with a stop
    /// there (`check::Place::stop`, `grammar::FirstSide::any_stop`). Default on
    /// (`--reask-stop-anywhere` turns it off).
    pub reask_stops_first: bool,
    /// With `reask_holds_agreed`: the re-ask's answer, continued after the steps it keeps,
    /// writes at least as many steps as the first answer made from its first disputed
    /// place on that no finding is about, and one for that place (`v2::Held::later`).
    /// Read in dev logs at stop 75, a re-ask about one step often ended the plan there
    /// (four steps became one).
    /// Default on (`--reask-may-shorten` turns it off).
    pub reask_keeps_steps: bool,
    /// With `said_only`, outside a conversation: a pick may be picked near (`near:`)
    /// only an object the person named in a clause with it (`check::anchors_said`;
    /// default on; `--anchors-anywhere` turns it off).
    pub anchors_of_said: bool,
    /// With `said_only`, outside a conversation: a pick takes no colour (kept or
    /// excluded) that the person said only right before other objects' names
    /// (`check::colour_said_only_of`: "the wheelchair closest to the blue hospital bed";
    /// default on; `--colours-of-others-allowed` turns it off).
    pub colours_of_others: bool,
    /// The re-ask, and every draw after it, moves back to where the plan began where
    /// the first answer did in a step no finding is about: no word check sees a
    /// missing move back, so a re-ask that dropped it was accepted (default on;
    /// `--reask-may-drop-return` turns it off).
    pub reask_keeps_return: bool,
    /// The objects line's colours are the person's (default on; `--any-tuple-colours`
    /// turns it off).
    pub said_tuple_colours: bool,
    /// A pick selects only on the colours its objects have on the map, and excludes
    /// only one that tells them apart (default on; `--any-pick-colours` turns it off):
    /// [`Vocabulary::map_colours`](crate::v2::grammar::Vocabulary::map_colours).
    pub map_colours: bool,
    /// Answers drawn again after the greedy answer and the re-ask still disagree with
    /// the checks, before the person is asked (default 1): each is the re-ask's request
    /// (the first request with `reask` off) sampled at `redraw_temperature` with its
    /// own seed (1, 2, ...), so a run repeats.
    /// The first draw the checks accept is the plan; no draw is changed. Measured on
    /// held-out v2 (dev): 3 draws mended 2 of 13 tasks, both with the first draw
    /// (README, "The language layer").
    pub redraws: u32,
    /// The temperature of those draws (default 0.7).
    pub redraw_temperature: f32,
    /// After the re-ask, before the sampled redraws: one greedy answer to the first
    /// request with the worked examples in reverse order, under the re-ask's grammar
    /// (default on). A different prompt gives a different greedy answer; the checks judge
    /// it as any other. Measured on held-out v2's 19 re-asked tasks (dev): README, "The
    /// language layer".
    pub reversed_draw: bool,
    /// Each answer in two steps under the grammar (default off until judged on the
    /// untuned sets; `--follow-objects`): the objects line, then
    /// the plan under a grammar narrowed by that line (`v2::follow_objects`): a pick of
    /// a name whose every tuple gives a colour selects on one of those colours, kept or
    /// excluded. The model writes both parts; the plan's grammar holds it to its own
    /// objects line, as the checks would. The answer is one text, the second request
    /// continuing the first (a prefix-caching backend evaluates only the new tokens).
    pub follow_objects: bool,
    /// The first answer's picks of a name said only with a colour right before it ("the
    /// yellow table closest to the counter") must select on one of the colours said of
    /// it (`check::labels_always_coloured`): the re-ask's bar for a dropped colour,
    /// given from the first answer on (default off until judged; `--said-colours-required`).
    /// Outside a conversation only.
    pub said_colours_required: bool,
    /// The re-ask keeps what no finding disputes (default on; `--reask-whole` turns it
    /// off): where every finding is about a step of the plan (`check::Finding::about`),
    /// the re-ask's answer begins with the first answer's objects line and its steps
    /// before the first disputed one, as the model wrote them, and the model writes the
    /// rest under the re-ask's grammar (`v2::held_answer`). The checks judge the whole
    /// answer as any other. Measured on held-out v9 (dev, stop 68): re-asks that mended
    /// their finding broke a step no finding was about (a count, a colour, a room).
    pub reask_holds_agreed: bool,
}

impl Default for PlanOptions {
    fn default() -> Self {
        Self {
            reask: true,
            extract_max_tokens: 96,
            plan_max_tokens: 384,
            dry_run: true,
            examples: None,
            answer_grammar: true,
            llguidance: true,
            said_only: true,
            said_colours: true,
            said_exclusions: true,
            directions_of_said: true,
            regions_of_said: true,
            names_of_said: true,
            last_room_stop: true,
            counts_of_said: true,
            far_ends_of_said: true,
            side_stops_of_said: false,
            first_side_stop: true,
            pairs_of_said: true,
            pair_stops_barred: false,
            orders_of_said: true,
            said_object_words: true,
            extraction_reask: true,
            reask_stops_first: true,
            reask_keeps_steps: true,
            anchors_of_said: true,
            colours_of_others: true,
            reask_keeps_return: true,
            said_tuple_colours: true,
            map_colours: true,
            redraws: 1,
            redraw_temperature: 0.7,
            reversed_draw: true,
            follow_objects: false,
            said_colours_required: false,
            reask_holds_agreed: true,
        }
    }
}

/// What a plan is made against.
#[derive(Debug, Clone)]
pub struct PlanContext<'a> {
    /// The map.
    pub map: &'a IvlMap,
    /// The robot whose copy dry-runs candidate plans (its pose is the start pose).
    pub robot: Option<&'a SimRobot>,
    /// The robot's pose (used when `robot` is `None`).
    pub pose: Pose,
    /// A summary of the conversation so far (see [`crate::Session`]).
    pub history: Option<String>,
    /// Object ids the conversation visited, which a v2 plan may name with
    /// `get_instance` (see [`crate::Session::references`]).
    pub references: Vec<u32>,
    /// An instruction this one may answer: the conversation's last, which got a
    /// question or a refusal instead of a plan ([`crate::Session::not_done`]). Its words
    /// count as said for what a plan may select on (colours, counts, orders, rooms: the
    /// grammar's narrowing and the checks of what the person did not say), never as
    /// asked for ("i meant the two red ones" after "the two black chairs" need not be
    /// black).
    pub earlier: Option<String>,
    /// Knobs.
    pub options: PlanOptions,
}

impl<'a> PlanContext<'a> {
    /// A context on `map` with the robot at the map's start pose, no dry run robot, no
    /// history, default options.
    #[must_use]
    pub fn new(map: &'a IvlMap) -> Self {
        Self {
            map,
            robot: None,
            pose: map.start_pose,
            history: None,
            references: Vec::new(),
            earlier: None,
            options: PlanOptions::default(),
        }
    }

    /// With a robot to dry-run candidate plans on (its pose becomes the pose).
    #[must_use]
    pub fn with_robot(mut self, robot: &'a SimRobot) -> Self {
        use map_core::Robot as _;
        self.pose = robot.pose();
        self.robot = Some(robot);
        self
    }

    pub(crate) fn pose(&self) -> Pose {
        use map_core::Robot as _;
        self.robot.map_or(self.pose, |r| r.pose())
    }
}

/// Where a plan's script came from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PlanSource {
    /// The model wrote it, after `repairs` further requests (0; 1 after the re-ask;
    /// more after the reversed examples' answer and the redraws).
    Llm {
        /// Requests after the first: the re-ask, the reversed examples' answer, then any
        /// redraws.
        repairs: u32,
    },
}

/// A checked plan for one instruction.
#[derive(Debug, Clone)]
pub struct PlannedInstruction {
    /// The instruction.
    pub instruction: String,
    /// The objects it mentions.
    pub tuples: Vec<Tuple>,
    /// The script: the model's typed plan printed as Rhai.
    pub script: String,
    /// The compiled, validated plan.
    pub plan: Plan,
    /// Where the script came from.
    pub source: PlanSource,
    /// Time and tokens spent.
    pub timing: Timing,
    /// Every answer the model gave, in order (the last is the one accepted).
    pub attempts: Vec<String>,
}

/// What the language layer makes of an instruction.
#[derive(Debug, Clone)]
pub enum Outcome {
    /// A plan that compiled, agrees with the instruction and the map, and (when a robot was
    /// given) dry-ran without error.
    Plan(Box<PlannedInstruction>),
    /// The instruction is ambiguous or asks for something the map does not quite hold (an
    /// ordinal past the count, a colour no such object has): ask the user.
    Question(String),
    /// The instruction cannot be done here (an object the map does not hold).
    Refusal(String),
}

impl Outcome {
    /// The plan, if this is one.
    #[must_use]
    pub fn plan(&self) -> Option<&PlannedInstruction> {
        match self {
            Outcome::Plan(p) => Some(p),
            _ => None,
        }
    }
}

/// How many instances labelled `label` have each colour ("unknown colour" for none), in
/// the order the colours first appear.
pub(crate) fn colour_counts(map: &IvlMap, label: &str) -> Vec<(String, usize)> {
    let mut colours: Vec<(String, usize)> = Vec::new();
    for i in map.instances.iter().filter(|i| i.label == label) {
        let c = i.colour.clone().unwrap_or_else(|| "unknown colour".into());
        match colours.iter_mut().find(|(x, _)| *x == c) {
            Some((_, k)) => *k += 1,
            None => colours.push((c, 1)),
        }
    }
    colours
}

/// "2 black, 1 red".
pub(crate) fn colour_list(colours: &[(String, usize)]) -> String {
    colours
        .iter()
        .map(|(c, k)| format!("{k} {c}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `label` for one instance, its plural for more.
pub(crate) fn noun(label: &str, n: usize) -> String {
    if n == 1 {
        label.to_string()
    } else {
        map_core::matcher::plural(label)
    }
}

/// A one-line summary of what the map holds, for prompts: categories with their colours,
/// then regions. Sorted, so it is the same for every instruction on the scene.
#[must_use]
pub fn scene_summary(map: &IvlMap) -> String {
    let mut parts = Vec::new();
    for (label, n) in map.label_counts() {
        let mut colours = colour_counts(map, &label);
        colours.sort();
        parts.push(format!("{} ({})", noun(&label, n), colour_list(&colours)));
    }
    let mut s = format!("objects: {}", parts.join("; "));
    if !map.regions.is_empty() {
        let names: Vec<&str> = map.regions.iter().map(|r| r.name.as_str()).collect();
        s.push_str(&format!(". regions: {}", names.join(", ")));
    }
    s
}

/// The (object, ordinal, colour) tuples of `instruction`: the objects line of the
/// one-call answer, asked for alone (no map; the extraction suites' task).
///
/// # Errors
/// [`LanguageError::Prompt`], [`LanguageError::Backend`], or [`LanguageError::Tuples`] when
/// the answer holds no usable list.
pub fn extract_tuples(
    backend: &dyn LlmBackend,
    prompts: &Prompts,
    instruction: &str,
    options: &PlanOptions,
) -> Result<(Vec<Tuple>, Timing), LanguageError> {
    crate::v2::extract(backend, prompts, instruction, options)
}

/// Plans one instruction with one constrained model call, at most one re-ask, the
/// answer with the worked examples reversed ([`PlanOptions::reversed_draw`]) and
/// [`PlanOptions::redraws`] sampled draws of the re-ask; what stays unsettled becomes a
/// question to the person (or a refusal, for an object the map does not hold), never a
/// different plan. See [`crate::v2`].
///
/// # Errors
/// [`LanguageError`]: prompts or backend.
pub fn plan_instruction(
    backend: &dyn LlmBackend,
    prompts: &Prompts,
    instruction: &str,
    ctx: &PlanContext<'_>,
) -> Result<Outcome, LanguageError> {
    crate::v2::plan_instruction(backend, prompts, instruction, ctx)
}
