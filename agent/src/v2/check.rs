//! Checks of a one-call answer: they compare, they never rewrite.
//!
//! Three sources of disagreement, each a [`Finding`] with one message for the model (the
//! targeted re-ask) and one for the person (the question asked when the re-ask does not
//! settle it):
//! - **words**: the instruction's colour, ordinal and superlative words against the typed
//!   plan's targets ("third" said, no target with ordinal 3);
//! - **the two parts**: the objects line against the plan (an object the plan never uses);
//! - **the map**: an object the map does not hold, a colour no such object has, and the
//!   dry run's first error.
//!
//! Nothing here edits the answer: the pipeline re-asks with the findings, then asks the
//! person.

use map_core::matcher::{canonical, is_colour_word};
use map_core::select::Selection;
use map_core::{IvlMap, ObjectOrder, Pose, QueryError};
use planner_dsl::typed::{Object, Side, Step, Target, TypedPlan};

use crate::pipeline::{colour_counts, colour_list, noun};
use crate::tuples::{
    counts_in, normalise_colour, parse_ordinal, parse_ordinal_with_order, said_count, Tuple,
};
use crate::words::words;

/// What kind of disagreement a finding is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FindingKind {
    /// The answer could not be read.
    Unreadable,
    /// A word of the instruction that no target reflects.
    Word,
    /// The objects line and the plan disagree.
    Parts,
    /// An object the map does not hold.
    UnknownObject,
    /// The map holds the object but not as asked (colour, count, exactly two).
    NotOnMap,
    /// The dry run failed.
    Runtime,
}

/// One disagreement.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Finding {
    /// Which kind.
    pub kind: FindingKind,
    /// For the re-ask: what to look at again.
    pub to_model: String,
    /// For the question: what is unclear, in the person's terms.
    pub to_user: String,
    /// A form of the answer the re-ask's grammar no longer offers (`None`: the re-ask
    /// has the first request's grammar).
    pub bar: Option<Bar>,
    /// Where in the plan the disagreement is (`None`: in no one step, such as an object
    /// the plan never picks, a missing move back, or the objects line). The re-ask keeps
    /// the steps before the first such place as the model wrote them
    /// ([`first_disputed_step`]).
    pub about: Option<About>,
}

/// Where in the plan a [`Finding`] is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum About {
    /// The picks of this map label (or region), its synonyms included, wherever the
    /// plan makes them (a stop, a `let`, an anchor).
    Label(String),
    /// The plan's step of this index (from 0): the dry run failed there.
    Step(usize),
    /// An object or room of this map label that the person named and the plan never
    /// picks: the steps for what the person named before it, in the order named, stand
    /// ([`first_disputed_step`]).
    Missing(String),
}

/// A form of the first answer that its re-ask's grammar bars, leaving the model every
/// other choice (measured: a re-ask that only says what was wrong mended 4 of 15
/// re-asked held-out v2 tasks; a constraint that requires content instead made the
/// default model loop).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Bar {
    /// Picks of this map label (and its synonyms) select on no colour the person did not
    /// say (`colour` and `not_colour`; `check::colour_said`).
    UnsaidColours {
        /// The map label.
        label: String,
    },
    /// Picks of this map label select on a colour, one the person said before that
    /// label's name ("the second black chair"; `check::colour_nouns`): the first answer
    /// dropped it. Unlike the other bar this one requires a key, so it is given only
    /// where the re-ask that described the finding had never mended it (measured: six
    /// dev tasks, none mended).
    ColourDropped {
        /// The map label.
        label: String,
    },
    /// No step stops at, faces or binds (`let`) an object of this map label (or its
    /// synonyms); it may still pick out another (`near:`). The person named it once,
    /// only to pick out another object, and the first answer stopped there too
    /// (`check_anchor_stops`; measured without the bar on held-out v3, dev: the re-ask
    /// that said so left both of its plans as they were).
    AnchorStop {
        /// The map label.
        label: String,
    },
    /// No selection counts from the end (a negative ordinal, the objects line's "last"):
    /// every count from the end the person said is "furthest" before a side ("the shelf
    /// furthest north"), the first in the order that starts there
    /// (`check::ends_said_of_sides`). Measured without the bar on held-out v3 (dev): the
    /// re-asks of "furthest east" wrote the last east-first (the westernmost) in each of
    /// their draws.
    CountFromStart,
    /// No `move_to_object` takes an object of this map label (or its synonyms), nor a
    /// `let` binds one; a side move, a face or an anchor still may. The person asked to
    /// stop at a side of it, and the first answer had no move to that side
    /// (`check_side_moves`). Not measured on its own: on held-out v8 (dev) ht06 the
    /// first answer had the side move and a re-ask for other findings dropped it, where
    /// a bar from the first answer's findings does not reach; the two answers after
    /// that kept the plain stop.
    SideStop {
        /// The map label.
        label: String,
        /// The side the person asked for: a re-ask's continuation from that label's
        /// picks begins with the move to it (`Vocabulary::first_side`). Held-out v16
        /// (dev) va12: with only the plain stop barred, the model that began
        /// `move_to_object(` went on with a saddle display nobody named, and the task
        /// ended in a question.
        side: planner_dsl::typed::Side,
    },
    /// The person asked to stop between the two of this map label, named only there
    /// (`check::pairs_said_between`), and the plan stops between nothing: the re-ask's
    /// continuation from that label's picks (or from where the plan lacks it) begins
    /// with `move_between_the_two` of it (`Vocabulary::first_side`). Held-out v13 (dev
    /// since its third run) nb11 and na11: the finding, placed nowhere, sent whole
    /// answers back, and their re-asks and draws lost the pair or other steps.
    PairStop {
        /// The map label.
        label: String,
    },
}

impl Finding {
    pub(crate) fn new(
        kind: FindingKind,
        to_model: impl Into<String>,
        to_user: impl Into<String>,
    ) -> Self {
        Self {
            kind,
            to_model: to_model.into(),
            to_user: to_user.into(),
            bar: None,
            about: None,
        }
    }

    /// With its bar; a bar of one label also places the finding at that label's picks.
    fn barring(mut self, bar: Bar) -> Self {
        if self.about.is_none() {
            self.about = match &bar {
                Bar::UnsaidColours { label }
                | Bar::ColourDropped { label }
                | Bar::AnchorStop { label }
                | Bar::SideStop { label, .. }
                | Bar::PairStop { label } => Some(About::Label(label.clone())),
                Bar::CountFromStart => None,
            };
        }
        self.bar = Some(bar);
        self
    }

    /// Placed at the picks of `label` (see [`About::Label`]).
    pub(crate) fn about_label(mut self, label: Option<String>) -> Self {
        if let Some(l) = label {
            self.about = Some(About::Label(l));
        }
        self
    }

    /// Placed after the steps for what was named before `label`, which the plan lacks
    /// (see [`About::Missing`]).
    fn missing(mut self, label: String) -> Self {
        self.about = Some(About::Missing(label));
        self
    }

    /// Placed at the step of `plan` that holds the target `t`, where one does (a
    /// reference into `plan`): a finding about one pick disputes that step, not an
    /// earlier pick of the same label ("the chair, then the red sofa, then the chair"
    /// with red on the second chair).
    fn at_target(self, plan: &TypedPlan, t: &Target) -> Self {
        match step_of(plan, t) {
            Some(i) => self.at_step(i),
            None => self,
        }
    }

    /// Placed at the plan's step `index` (see [`About::Step`]).
    #[must_use]
    pub fn at_step(mut self, index: usize) -> Self {
        self.about = Some(About::Step(index));
        self
    }
}

/// The index of the first step of `plan` that one of `findings` is about, where every
/// finding is about some place in the plan ([`Finding::about`]) and is of the plan alone
/// (not of the map, or an answer that did not read; of the objects line only where it
/// lists what the plan lacks): the steps before it are those no finding disputes.
/// `None` where a finding is about no place (a missing move back, a "between" with no
/// stop between). A finding about the picks of a label no step picks is placed as what
/// the plan lacks.
///
/// A step picks a label when one of its targets (an anchor's, a room's too), its bare
/// names or its instance ids are of that label. For an object the plan lacks
/// ([`About::Missing`]), the steps stand that pick, in order, what the person named
/// before it, in the order named ([`name_mentions`]; design.md: the order of mention is
/// the order of the visits), less the last of them, which the missing object may belong
/// to ("the swivel chair closest to the white printer" written without the printer),
/// unless the missing object is the only one its clause ([`clauses`]) names ("then into
/// triage", "and call it a day in the pro shop"): then a place of its own after them.
#[must_use]
pub fn first_disputed_step(
    map: &IvlMap,
    instruction: &str,
    findings: &[Finding],
    plan: &TypedPlan,
    pose: Pose,
) -> Option<usize> {
    disputed_steps(map, instruction, findings, plan, pose)?
        .into_iter()
        .min()
}

/// The place in `plan` of each of `findings`, as [`first_disputed_step`] places them
/// (a step a finding is about, or where a step the plan lacks would go), in the order of
/// `findings`; `None` where a finding is about no place. Empty where there is no finding.
#[must_use]
pub fn disputed_steps(
    map: &IvlMap,
    instruction: &str,
    findings: &[Finding],
    plan: &TypedPlan,
    pose: Pose,
) -> Option<Vec<usize>> {
    Some(
        disputed_places(map, instruction, findings, plan, pose)?
            .into_iter()
            .map(|p| p.at)
            .collect(),
    )
}

/// Where in a plan a finding is ([`disputed_places`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Place {
    /// The step it is about, or the step before which the one the plan lacks goes (the
    /// plan's length: after its last).
    pub at: usize,
    /// Whether it is about something the plan lacks ([`About::Missing`], or the picks of
    /// a label no step picks): a step goes in before `at`, and the step at `at` stands.
    pub lacking: bool,
    /// Where what the plan lacks is the only thing its clause names ("then the black
    /// radar screen") and every step before `at` stands for what was named before it:
    /// its label, a stop of its own at `at`.
    pub stop: Option<String>,
}

/// [`disputed_steps`], each place with whether the plan lacks what it is about.
#[must_use]
pub fn disputed_places(
    map: &IvlMap,
    instruction: &str,
    findings: &[Finding],
    plan: &TypedPlan,
    pose: Pose,
) -> Option<Vec<Place>> {
    let labels = |s: &Step| step_labels(map, s, pose);
    // The room the robot is in, said first ("We're both in the booking hall. ..."), is
    // no stop the plan's steps stand for ([`start_room_named_first`]). Held-out v15
    // (dev) rc04: counted as the first thing named, no step stood for it, so the re-ask
    // for "..., and finish in the parts store" kept no step and lost the plan.
    let w = words(instruction);
    let here = start_room_named_first(map, &w, pose);
    let mentions: Vec<String> = name_mentions(map, &w, pose)
        .into_iter()
        .map(|(_, l)| l)
        .skip(usize::from(here.is_some()))
        .collect();
    // The labels named in each clause, where they are the instruction's in order.
    let mut per_clause: Vec<Vec<String>> = clauses(instruction)
        .iter()
        .map(|w| {
            name_mentions(map, w, pose)
                .into_iter()
                .map(|(_, l)| l)
                .collect()
        })
        .collect();
    if let Some(here) = here {
        if let Some(c) = per_clause.iter_mut().find(|c| !c.is_empty()) {
            if c[0] == here {
                c.remove(0);
            }
        }
    }
    // For each label named, whether it is the only one its clause names ("then into
    // triage", "and call it a day in the pro shop"): a place of its own, not one of the
    // object before it. None alone where the clauses do not name the labels in order.
    let alone_at: Vec<bool> = if per_clause.concat() == mentions {
        per_clause
            .iter()
            .flat_map(|c| std::iter::repeat_n(c.len() == 1, c.len()))
            .collect()
    } else {
        Vec::new()
    };
    let alone = |k: usize| alone_at.get(k).copied().unwrap_or(false);
    // Where the plan lacks `l`: after the steps for what was named before it.
    // With whether every step before that place stands for what was named before it
    // (a stop said alone there is the next one to make).
    let missing = |l: &str| -> Option<(usize, bool)> {
        let named_at = mentions.iter().position(|m| m == l)?;
        let mut m = 0;
        let mut agreed: usize = 0;
        for s in &plan.steps {
            let ls = labels(s);
            if ls.is_empty() || m + ls.len() > named_at || mentions[m..m + ls.len()] != ls[..] {
                break;
            }
            m += ls.len();
            agreed += 1;
        }
        let next = m == named_at && alone(named_at);
        Some(if m == named_at && !next {
            (agreed.saturating_sub(1), false)
        } else {
            (agreed, next)
        })
    };
    let mended = |at: usize| Place {
        at,
        lacking: false,
        stop: None,
    };
    let lacking = |l: &str| -> Option<Place> {
        let (at, next) = missing(l)?;
        Some(Place {
            at,
            lacking: true,
            stop: next.then(|| l.to_string()),
        })
    };
    let mut out = Vec::new();
    for f in findings {
        let about = f.about.as_ref()?;
        match (f.kind, about) {
            (FindingKind::Word | FindingKind::Runtime, _)
            | (FindingKind::Parts, About::Missing(_)) => {}
            _ => return None,
        }
        out.push(match about {
            About::Step(i) => mended((*i < plan.steps.len()).then_some(*i)?),
            About::Label(l) => match plan.steps.iter().position(|s| labels(s).contains(l)) {
                Some(i) => mended(i),
                // About the picks of a label the plan has none of ("the blue hospital
                // bed" said, no hospital bed picked): placed as what the plan lacks.
                None => lacking(l)?,
            },
            About::Missing(l) => lacking(l)?,
        });
    }
    Some(out)
}

/// The labels a step picks, in the order a person names them: each target's, then its
/// room's (`region:`), then its anchors'; its bare names (rooms too); its instance ids'.
fn step_labels(map: &IvlMap, s: &Step, pose: Pose) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for t in s.targets() {
        out.extend(label_of(map, &t.name, pose));
        out.extend(t.region.as_deref().and_then(|r| label_of(map, r, pose)));
    }
    out.extend(s.names().into_iter().filter_map(|n| label_of(map, n, pose)));
    for o in s.objects() {
        if let Object::Instance(id) = o {
            out.extend(map.instance_by_id(*id).map(|i| i.label.clone()));
        }
    }
    out
}

/// Steps that pick an object the person never named: a target's (an anchor's too, a
/// `near:` pick) or a bare name's label that no word or two of the instruction name
/// ([`named_labels`]: the name, a synonym, a typo). Outside a conversation only (there
/// the references name what was visited). A room that filters a pick (`region:`) is not
/// judged here ([`unsaid_regions`] is).
/// Held-out v13 (dev since its third run) na11: "then the white rental counter, then the
/// waxing room" ended `move_to_object(get_obj("wax heater", #{region: "waxing room"}))`,
/// a wax heater nobody named, and no check said so. On the ten dev navigation suites
/// (1,395 stops at objects), every stop's label is one the instruction names.
fn check_unnamed_stops(
    map: &IvlMap,
    instruction: &str,
    plan: &TypedPlan,
    pose: Pose,
) -> Vec<Finding> {
    let named = named_labels(map, &words(instruction), pose);
    let mut out = Vec::new();
    for (i, s) in plan.steps.iter().enumerate() {
        let names = s
            .targets()
            .into_iter()
            .map(|t| (t.name.as_str(), t.region.as_deref()))
            .chain(s.names().into_iter().map(|n| (n, None)));
        for (n, region) in names {
            let Some(label) = label_of(map, n, pose) else {
                continue;
            };
            if named.contains(&label) {
                continue;
            }
            let what = if is_region(map, &label) {
                format!("the {label}")
            } else {
                format!("{} {label}", a_or_an(&label))
            };
            // A pick in a room the person named, where they named no object there: the
            // room itself is the stop ("then the waxing room").
            let to_model = match region.filter(|r| named.iter().any(|l| l == r)) {
                Some(r) => format!("the plan goes to {what} in the {r}, but the person never named {} {label}: leave that stop out; where their words ask to go into the {r} itself, write move_to_object(\"{r}\")", a_or_an(&label)),
                None => format!("the plan picks {what}, but the person never named one: leave it out and pick only what their words name"),
            };
            // Placed at this step; the re-ask may not stop at the label again (the bar
            // of an anchor's stop: the stop goes, and the floor does not count it).
            // Held-out v13 (dev) na06: with the note alone, the held re-ask wrote the
            // same stop at a log basket nobody named again, and the task ended in a
            // question.
            out.push(
                Finding::new(
                    FindingKind::Word,
                    to_model,
                    format!("should I go to {what}? I did not hear you name one"),
                )
                .at_step(i)
                .barring(Bar::AnchorStop { label }),
            );
            break;
        }
    }
    out
}

/// Objects the person named more often than the plan picks them: a label said k times
/// ([`name_mentions`]) that the plan's steps pick (targets, anchors, rooms, bare names:
/// [`step_labels`]) fewer times. Outside a conversation only ("the same chair again").
/// Held-out v13 (dev since its third run) na04: "Stop A: the penultimate ski rack. ...
/// Stop C: the red ski rack in the boot room." was written as one ski rack,
/// `#{ordinal: -2, colour: "red"}`, in every run. On 212 plans of the dev runs read for
/// it, only na04's were found.
///
/// A mention counts here only where its words are a whole name of the object (its label
/// or a synonym, [`said_whole_name`]): the last word of a name alone may be another
/// word ("go and stand centred between the two red wrapping stations, then the cactus
/// stand" says one cactus stand). Held-out v16 (dev) vb05: that instruction's right
/// pair stop was re-asked with "you named the cactus stand 2 times" beside it, and the
/// re-ask lost the task.
fn check_names_said_again(
    map: &IvlMap,
    instruction: &str,
    plan: &TypedPlan,
    pose: Pose,
) -> Vec<Finding> {
    let w = words(instruction);
    let mut mentions: Vec<(usize, String)> = name_mentions_with_len(map, &w, pose)
        .into_iter()
        .filter(|(k, len, l)| said_whole_name(&w[*k..*k + *len], l))
        .map(|(k, _, l)| (k, l))
        .collect();
    // The room the robot is in, said first, is where it is, not a stop or a pick's
    // room: held-out v17 (dev) wa04 and wc10, "you and me are in the tack room. ...
    // the black saddle rack in the tack room" were re-asked as the tack room named
    // twice and picked once, and both ended in questions.
    if let Some(here) = start_room_named_first(map, &w, pose) {
        if mentions.first().is_some_and(|(_, l)| *l == here) {
            mentions.remove(0);
        }
    }
    let mut out = Vec::new();
    let mut seen: Vec<&String> = Vec::new();
    for l in mentions.iter().map(|(_, l)| l) {
        if seen.contains(&l) {
            continue;
        }
        seen.push(l);
        let said = mentions.iter().filter(|(_, x)| x == l).count();
        if said < 2 {
            continue;
        }
        let picked: usize = plan
            .steps
            .iter()
            .map(|s| step_labels(map, s, pose).iter().filter(|x| *x == l).count())
            .sum();
        if picked < said {
            out.push(Finding::new(
                FindingKind::Word,
                format!("the person named the {l} {said} times, but the plan picks {} {l} {picked} time(s): pick one for each time they name it, in the order they name them", a_or_an(l)),
                format!("you named the {l} {said} times: which ones do you mean?"),
            ));
        }
    }
    out
}

/// Whether the words `said` are a whole name of the map name `label`: the label itself
/// or one of its synonyms ([`crate::v2::grammar::label_names`]), singular or plural,
/// after any words said before it ("black sofa"), and not a part of one ("stand" of
/// "cactus stand").
fn said_whole_name(said: &[String], label: &str) -> bool {
    let said = map_core::matcher::singular(&said.join(" "));
    let ends_in = |n: &str| {
        let n = map_core::matcher::singular(n);
        said == n || said.ends_with(&format!(" {n}"))
    };
    ends_in(label)
        || crate::v2::grammar::label_names(label.to_string())
            .iter()
            .any(|n| ends_in(n))
}

/// Counts that the person said of an object, not right after "the" or "number" (those
/// [`check_words`] reads: "the third chair"), that the objects line also gives that
/// object, where no pick of it in the plan counts so: "the bucket that comes last when
/// you go from west to east" listed `(bucket, last, None)` and planned
/// `get_obj("bucket", #{order: "west_to_east"})`, the first from the west (held-out v16,
/// dev, vb11; no check saw it). The words and the model's own line agree on the count;
/// the plan is what disagrees. Only in a clause that names that one object
/// ([`clauses`]), and "last" only where words follow it in its clause ("and the
/// workroom last" says when, not which).
fn check_listed_counts_unplanned(
    map: &IvlMap,
    instruction: &str,
    tuples: &[Tuple],
    plan: &TypedPlan,
    pose: Pose,
) -> Vec<Finding> {
    let mut out: Vec<Finding> = Vec::new();
    for c in clauses(instruction) {
        let named = object_mentions(map, &c, pose);
        let [(_, label)] = named.as_slice() else {
            continue;
        };
        let name_words: Vec<&str> = label.split(' ').collect();
        let of_label: Vec<&Target> = targets(plan)
            .into_iter()
            .filter(|t| picks(map, pose, label)(t))
            .collect();
        let mut i = 0;
        while i < c.len() {
            let x = &c[i];
            let prev = i.checked_sub(1).map_or("", |j| c[j].as_str());
            // A count from the end in more words ("one shy of the end").
            let phrase = crate::tuples::count_from_the_end_at(&c, i);
            let start = i;
            i += phrase.map_or(1, |(_, len)| len);
            if matches!(prev, "the" | "number" | "no" | "#") || name_words.contains(&x.as_str()) {
                continue;
            }
            let k = match (phrase, x.as_str()) {
                (Some((k, _)), _) => Some(k),
                (None, "last") => (start + 1 < c.len()).then_some(-1),
                _ => parse_ordinal(x)
                    .ok()
                    .flatten()
                    .filter(|_| in_ordinal_form(x))
                    .or_else(|| said_count(x).filter(|&k| k == -2)),
            };
            let Some(k) = k.filter(|&k| k != 0 && k != 1) else {
                continue;
            };
            // The line counts from the other end in an order ("(table, 2, None,
            // east_to_west)" for the second to last from the west), or as said.
            let from_other_end = |t: &Tuple| {
                k < 0
                    && t.ordinal == Some(-k)
                    && t.order
                        .as_deref()
                        .and_then(|o| ObjectOrder::parse(o).ok())
                        .is_some_and(|o| o != ObjectOrder::NearToFar)
            };
            let listed = tuples.iter().any(|t| {
                (t.ordinal == Some(k) || from_other_end(t))
                    && object_label(map, &t.object, pose).as_deref() == Some(label)
            });
            if !listed || of_label.is_empty() || of_label.iter().any(|t| counts_as_said(t, k)) {
                continue;
            }
            let wanted = ordinal_wanted(k);
            let f = Finding::new(
                FindingKind::Word,
                format!("the person said \"{}\", and the objects line counts the {label} {k}, but no {label} in the plan has ordinal {wanted}", c.join(" ")),
                format!("which {label} is the {x}? there are {}", describe_label(map, label)),
            )
            .about_label(Some(label.clone()));
            if !out.contains(&f) {
                out.push(f);
            }
        }
    }
    out
}

/// Whether `word` is a count in an ordinal form ("third", "3rd", "second"), not a
/// bare number ("the two tables" counts nothing).
fn in_ordinal_form(word: &str) -> bool {
    ["st", "nd", "rd", "th"].iter().any(|e| word.ends_with(e)) || word == "second"
}

/// Whether target `t` counts as the person's count `k`: k-th (either end where `k` is
/// positive), or from the end (`-k`, or `k` counted from the other end of an order the
/// person gave), or the k-th visited ("the second chair you visited").
fn counts_as_said(t: &Target, k: i64) -> bool {
    if k < 0 {
        t.ordinal == k || t.visited == k || (t.ordinal == -k && t.order != ObjectOrder::NearToFar)
    } else {
        t.ordinal.abs() == k || t.visited == k
    }
}

/// The ordinal a re-ask asks for after the count `k`: "-2 (or 2 counted from the other
/// end)", or "3".
fn ordinal_wanted(k: i64) -> String {
    if k < 0 {
        format!("{k} (or {} counted from the other end)", -k)
    } else {
        k.to_string()
    }
}

/// The article before `word`: "an" before a vowel ("an ironing board"), else "a".
fn a_or_an(word: &str) -> &'static str {
    if word.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    }
}

/// Whether two colour words name the same colour ("grey" and "gray").
pub(crate) fn same_colour(a: Option<&str>, b: &str) -> bool {
    a.is_some_and(|a| canonical(a) == canonical(b))
}

/// The map label (or region name) a name means, if the map holds it.
fn label_of(map: &IvlMap, name: &str, pose: Pose) -> Option<String> {
    if let Ok(r) = map.find_region(name) {
        return Some(r.name.clone());
    }
    map.get_obj_attributes(name, 0, None, ObjectOrder::default(), pose)
        .ok()
        .map(|i| i.label.clone())
}

/// The map label a word the person typed means, allowing a typo ("tabel", "chiar"): the
/// exact reading first ([`label_of`]), else the one label or region within a small edit
/// distance (1 for words up to 5 letters, 2 beyond), if exactly one is.
fn label_of_typed(map: &IvlMap, name: &str, pose: Pose) -> Option<String> {
    if let Some(l) = label_of(map, name, pose) {
        return Some(l);
    }
    let n = map_core::matcher::singular(&map_core::matcher::normalise(name));
    let limit = if n.chars().count() <= 5 { 1 } else { 2 };
    let close: Vec<String> = names_on_map(map)
        .into_iter()
        .filter(|l| strsim::damerau_levenshtein(&n, l) <= limit)
        .collect();
    match close.as_slice() {
        [one] => Some(one.clone()),
        _ => None,
    }
}

/// Whether a target picks an object of `label`.
fn picks<'a>(map: &'a IvlMap, pose: Pose, label: &'a str) -> impl Fn(&Target) -> bool + 'a {
    move |t| label_of(map, &t.name, pose).as_deref() == Some(label)
}

/// Whether a target is on the object a word is said of: any target when the words name
/// no object the plan picks (`of` is None), else a target of that object.
fn on_said<'a>(map: &'a IvlMap, pose: Pose, of: Option<&'a str>) -> impl Fn(&Target) -> bool + 'a {
    move |t| of.is_none_or(|l| picks(map, pose, l)(t))
}

/// The said object's label, kept only where some target of the plan picks it.
fn said_and_picked(
    map: &IvlMap,
    pose: Pose,
    label: Option<String>,
    any_target: &AnyTarget<'_>,
) -> Option<String> {
    label.filter(|l| any_target(&picks(map, pose, l)))
}

/// Every target of the plan with the label it means.
fn targets(plan: &TypedPlan) -> Vec<&Target> {
    plan.steps.iter().flat_map(Step::targets).collect()
}

/// The labels the plan names, once per mention, step by step ([`step_labels`]).
fn plan_labels(map: &IvlMap, plan: &TypedPlan, pose: Pose) -> Vec<String> {
    plan.steps
        .iter()
        .flat_map(|s| step_labels(map, s, pose))
        .collect()
}

/// A short list of what the map holds of `label`, for questions: "3 chairs (2 black, 1 red)".
#[must_use]
pub fn describe_label(map: &IvlMap, label: &str) -> String {
    let colours = colour_counts(map, label);
    let n: usize = colours.iter().map(|(_, k)| k).sum();
    format!("{n} {} ({})", noun(label, n), colour_list(&colours))
}

/// What the map holds of colour `c` (said as `word`), for questions: "I see 1 orange
/// chair and 2 orange tables", or "I see nothing orange".
fn describe_colour(map: &IvlMap, c: &str, word: &str) -> String {
    let held: Vec<String> = map
        .label_counts()
        .into_iter()
        .filter_map(|(label, _)| {
            let n = map
                .instances
                .iter()
                .filter(|i| i.label == label && same_colour(i.colour.as_deref(), c))
                .count();
            (n > 0).then(|| format!("{n} {word} {}", noun(&label, n)))
        })
        .collect();
    match held.as_slice() {
        [] => format!("I see nothing {word}"),
        [one] => format!("I see {one}"),
        [rest @ .., last] => format!("I see {} and {last}", rest.join(", ")),
    }
}

/// The labels the map holds, then its regions.
fn names_on_map(map: &IvlMap) -> Vec<String> {
    let mut v: Vec<String> = map.label_counts().into_iter().map(|(l, _)| l).collect();
    v.extend(map.regions.iter().map(|r| r.name.clone()));
    v
}

/// The words of the map's object names, labels and their synonyms ([`region_said`]'s
/// words read only as themselves).
pub(crate) fn object_name_words(map: &IvlMap) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for (label, _) in map.label_counts() {
        for name in map_core::matcher::synonyms(&label)
            .into_iter()
            .map(str::to_string)
            .chain([label.clone()])
        {
            out.extend(words(&name));
        }
    }
    out.sort();
    out.dedup();
    out
}

/// The labels and regions the map holds, for a refusal.
fn map_names(map: &IvlMap) -> String {
    names_on_map(map).join(", ")
}

/// The objects line against the map and the plan: an object the person named (a word of
/// the instruction) that the map lacks, a said colour the map has no such object in,
/// and a named object the plan never goes to or uses ([`named_labels`]). The line's
/// ordinals, and its objects and colours the person did not say, are the model's notes:
/// the words check ([`check_words`]) compares the plan itself with what the person said.
fn check_tuples(
    map: &IvlMap,
    instruction: &str,
    tuples: &[Tuple],
    plan: &TypedPlan,
    pose: Pose,
    visited: &[u32],
    refs: &[u32],
) -> Vec<Finding> {
    let mut out = Vec::new();
    // In a conversation, an object the person refers back to ("the table you just
    // visited", "where we started") is reached by id or by position.
    let by_reference = plan.steps.iter().any(|s| {
        matches!(s, Step::MoveTo(_))
            || s.objects()
                .iter()
                .any(|o| matches!(o, planner_dsl::typed::Object::Instance(_)))
    });
    let accounts = Accounts::new(map, instruction, plan, pose);
    // An empty objects line for a plan that picks what the person named.
    if tuples.is_empty() {
        let named: Vec<String> = said_names(map, &words(instruction))
            .into_iter()
            .filter(|(_, label)| accounts.used.contains(label))
            .map(|(said, _)| said)
            .collect();
        if !named.is_empty() {
            out.push(Finding::new(
                FindingKind::Parts,
                format!(
                    "the objects line is empty, but the person named {}: list each object they named",
                    named.join(", ")
                ),
                format!("is it the {} you mean?", named.join(" and the ")),
            ));
        }
    }
    let w = words(instruction);
    let said = w.join(" ");
    let said_words = format!(" {said} ");
    let known = colours_of(map, refs);
    let colour_is_said = colour_said(instruction, &known);
    let named = named_labels(map, &w, pose);
    // A colour said only right before other objects' names ("the crate next to the blue
    // cabinet": blue, of the cabinet) is not said of a tuple's object: a tuple giving it
    // one is the model's note, and the plan is judged on its own (held-out v7, dev,
    // hq08: `(crate, None, blue)` beside a right plan sent it to a re-ask that dropped
    // the cabinet, then a question).
    // A colour said after a word that excludes ("a stretcher that isn't green, then
    // the drip stand nearest to the green stretcher") is a colour of nothing said: such
    // a mention counts neither way (held-out v10, dev, ka10: `(drip stand, None,
    // green)` beside a right plan was refused as a drip stand the map lacks, and the
    // re-asks lost the plan).
    let mentions = colour_mentions_excluded(map, instruction, pose);
    let only_of_others = |c: &str, label: &str| {
        let c = canonical(c);
        let of: Vec<&(String, Option<String>, bool)> =
            mentions.iter().filter(|(x, _, _)| *x == c).collect();
        !of.is_empty()
            && of
                .iter()
                .filter(|(_, _, excluded)| !excluded)
                .all(|(_, l, _)| l.as_deref().is_some_and(|l| l != label))
    };
    for t in tuples {
        // A colour is not an object ("the sofa, the red one" listed as (red, ...)).
        if is_colour_word(&t.object) {
            continue;
        }
        // Only what the person said counts: a word the model made up as an object
        // ("start" for "where you started") is not a request for it; a word the person
        // typed may be a typo of a name the map holds.
        let literal = said_words.contains(&format!(" {} ", t.object))
            || said_words.contains(&format!(" {} ", map_core::matcher::plural(&t.object)));
        let label = if literal {
            label_of_typed(map, &t.object, pose)
        } else {
            label_of(map, &t.object, pose)
        };
        let Some(label) = label else {
            // The words of a clause that sends the robot back and names nothing on the
            // map ("and then back to your spawn point") name where it began, which a
            // plan that moves back goes to. Held-out v14 (dev) pa10: `(spawn point,
            // None, None)` beside a right plan was re-asked as an object the map lacks.
            let the_start = refs.is_empty()
                && plan_returns(plan)
                && clauses(instruction).iter().any(|c| {
                    let c = c.join(" ");
                    format!(" {c} ").contains(&format!(" {} ", t.object))
                        && return_said_on(map, &c, pose, false)
                });
            // Nor is a count word ("second", listed from "the second most distant
            // kiln") or a part of a map name the person said ("wheel" from "the wheel
            // set"): the line cut or misread a name the map holds, which the plan
            // and the words checks judge. Held-out v14 (dev) pb04 and v15 (dev) rc13:
            // each was refused as an object the map lacks.
            let in_said_name = || {
                let o = words(&t.object);
                !o.is_empty()
                    && name_spans(map, &w, pose)
                        .iter()
                        .any(|&(a, n)| w[a..a + n].windows(o.len()).any(|x| x == o.as_slice()))
            };
            let count_word =
                said_count(&t.object).is_some() || matches!(parse_ordinal(&t.object), Ok(Some(_)));
            if literal && !the_start && !count_word && !in_said_name() {
                out.push(Finding::new(
                    FindingKind::UnknownObject,
                    format!(
                        "there is no {} on this map (it holds: {}); if the person meant one of these, use its name in both parts",
                        t.object,
                        map_names(map)
                    ),
                    format!("I can't find a {} here; the map holds: {}", t.object, map_names(map)),
                ));
            }
            continue;
        };
        // The rest of the line is the model's own notes where the person did not name
        // the object ("living room" listed for "back to where you started") or did not
        // say the colour ("the biggest bed" listed as (bed, 1, white)): the plan is
        // what runs, and the words checks judge it. Measured on the dev sets: these two
        // findings alone sent right plans (people.nav's pp-hc7, held-out v2's hf09
        // re-ask) to a re-ask or a question.
        if !literal && !named.contains(&label) {
            continue;
        }
        let region = is_region(map, &label);
        if let Some(c) = t
            .colour
            .as_deref()
            .filter(|c| colour_is_said(c) && !only_of_others(c, &label))
        {
            // A colour said of nothing the words name ("the roll cage painted silver")
            // that the plan does not give this object is the line's note on the wrong
            // object: the words check judges whether any pick carries it. Held-out v14
            // (dev) pa09: `(parcel locker, 1, silver)` beside a plan with no silver
            // parcel locker was re-asked as a parcel locker the map lacks.
            let said_of_it = mentions.iter().any(|(x, l, excluded)| {
                !excluded && *x == canonical(c) && l.as_deref() == Some(label.as_str())
            });
            let carried = || {
                let of_label = picks(map, pose, &label);
                targets(plan)
                    .iter()
                    .any(|t| of_label(t) && same_colour(t.colour.as_deref(), c))
            };
            if !region
                && !map
                    .instances
                    .iter()
                    .any(|i| i.label == label && same_colour(i.colour.as_deref(), c))
                && (said_of_it || carried())
            {
                out.push(Finding::new(
                    FindingKind::NotOnMap,
                    format!(
                        "no {label} on this map is {c}: there are {}",
                        describe_label(map, &label)
                    ),
                    format!(
                        "I see no {c} {label}: there are {}",
                        describe_label(map, &label)
                    ),
                ));
                continue;
            }
        }
        if !accounts.has(map, &label, visited, by_reference.then_some(refs)) {
            let f = Finding::new(
                FindingKind::Parts,
                format!(
                    "the objects line lists {} but the plan does not use a {label}",
                    t.paper_form()
                ),
                format!("I am not sure what to do with the {}", t.object),
            );
            out.push(f.missing(label));
        }
    }
    out
}

/// The labels (and regions) a word or two of the instruction `w` name: the name itself,
/// a synonym ("couch" for the sofa), a compound ("armchair") or, for a word of four
/// letters or more that is not a colour, a typo ("tabel"). Shorter words are read
/// exactly: "to" is one edit from "tv", "red" from "bed". Read once per answer, not per
/// tuple.
pub(crate) fn named_labels(map: &IvlMap, w: &[String], pose: Pose) -> Vec<String> {
    let single = w.iter().filter(|x| !is_colour_word(x)).filter_map(|x| {
        if x.chars().count() >= 4 {
            label_of_typed(map, x, pose)
        } else {
            label_of(map, x, pose)
        }
    });
    let pairs = w
        .windows(2)
        .filter_map(|p| label_of(map, &p.join(" "), pose));
    let mut out: Vec<String> = single.chain(pairs).collect();
    out.sort();
    out.dedup();
    out
}

/// What a plan accounts for of the names the person said ([`Accounts::has`]): the
/// names it uses ([`plan_labels`], with the room the robot is in where it is named first,
/// [`start_room_named_first`]) and the regions said of each object
/// ([`regions_said_of`]). Read once per answer by [`check_tuples`] and [`check_names`].
struct Accounts {
    used: Vec<String>,
    said_of: Vec<(String, Vec<String>)>,
}

impl Accounts {
    fn new(map: &IvlMap, instruction: &str, plan: &TypedPlan, pose: Pose) -> Self {
        let mut used = plan_labels(map, plan, pose);
        used.extend(start_room_named_first(map, &words(instruction), pose));
        Self {
            used,
            said_of: regions_said_of(map, instruction, pose),
        }
    }

    /// Whether the plan accounts for `label`: it names it, its dry run reached one or,
    /// for a region, an object in it that the region is said of (`visited`), or, where
    /// the plan can reach earlier stops (`refs`: the conversation's instances, when the
    /// plan moves by id or position), the conversation visited one.
    fn has(&self, map: &IvlMap, label: &str, visited: &[u32], refs: Option<&[u32]>) -> bool {
        let is = |id: &u32| map.instance_by_id(*id).is_some_and(|i| i.label == label);
        // A region is accounted for when the plan stops at an object in it that the
        // person placed there ("the yellow table in the kitchen" on a map whose one
        // yellow table is there). A stop at some other object that happens to stand in
        // it is not a visit to the room: held-out v15 (dev) rc02, "the second axle
        // stand, then any parts shelf except the yellow one, and end up back in the
        // engine shed", left the shed out, and the axle stand in the shed hid it from
        // both checks.
        let inside = |id: &u32| {
            map.instance_by_id(*id).is_some_and(|i| {
                self.said_of
                    .iter()
                    .any(|(l, rs)| *l == i.label && rs.iter().any(|r| r == label))
                    && map
                        .regions
                        .iter()
                        .any(|r| r.name == label && r.polygon.contains(i.centroid))
            })
        };
        self.used.iter().any(|u| u == label)
            || visited.iter().any(|id| is(id) || inside(id))
            || refs.is_some_and(|r| r.iter().any(is))
    }
}

/// The colours the instruction says of a map object, with that object's label ("the
/// white chair": white, chair), as [`colour_noun`] reads them (colours in their canonical
/// spelling: grey as gray).
pub(crate) fn colour_nouns(map: &IvlMap, instruction: &str, pose: Pose) -> Vec<(String, String)> {
    colour_mentions(map, instruction, pose)
        .into_iter()
        .filter_map(|(c, label)| Some((c, label?)))
        .collect()
}

/// Each colour word of the instruction (canonical spelling), with the label of the map
/// object it is said of where [`colour_noun`] reads one ("the sofa, the red one": the
/// sofa; "the chair that's red": none).
fn colour_mentions(map: &IvlMap, instruction: &str, pose: Pose) -> Vec<(String, Option<String>)> {
    let w = words(instruction);
    (0..w.len())
        .filter(|&i| is_colour_word(&w[i]))
        .filter_map(|i| {
            let c = normalise_colour(&w[i])?;
            Some((canonical(&c), colour_noun(map, &w, i, pose).map(|(_, l)| l)))
        })
        .collect()
}

/// The labels a colour is said of, where every mention of it is right before a map
/// object's name ([`colour_mentions`]; "the wheelchair closest to the blue hospital bed":
/// blue, of the hospital bed); `None` where it is not said, or once said of no name.
pub(crate) fn colour_said_only_of(
    map: &IvlMap,
    instruction: &str,
    pose: Pose,
) -> impl Fn(&str) -> Option<Vec<String>> {
    let mentions = colour_mentions(map, instruction, pose);
    move |c: &str| {
        let c = canonical(c);
        let labels: Option<Vec<String>> = mentions
            .iter()
            .filter(|(x, _)| *x == c)
            .map(|(_, l)| l.clone())
            .collect();
        labels.filter(|l| !l.is_empty())
    }
}

/// Picks that keep a colour the person said only to exclude it ("a non-yellow skate
/// trainer", "the sofa that isn't red" written `colour: "yellow"`, `colour: "red"`):
/// [`colour_mentions_excluded`], every mention of that colour after a word that
/// excludes. The colour checks take `colour` and `not_colour` alike as carrying a said
/// colour, so none saw it: held-out v17 (dev) wb09.
fn check_excluded_colours_kept(
    map: &IvlMap,
    instruction: &str,
    plan: &TypedPlan,
    pose: Pose,
) -> Vec<Finding> {
    let mentions = colour_mentions_excluded(map, instruction, pose);
    let mut out: Vec<Finding> = Vec::new();
    for t in targets(plan) {
        let Some(c) = t.colour.as_deref() else {
            continue;
        };
        let of: Vec<&(String, Option<String>, bool)> = mentions
            .iter()
            .filter(|(x, _, _)| same_colour(Some(x), c))
            .collect();
        if of.is_empty() || !of.iter().all(|(_, _, excluded)| *excluded) {
            continue;
        }
        let f = Finding::new(
            FindingKind::Word,
            format!("the person said {c} only to exclude it, but the plan picks the {} with colour: \"{c}\": write not_colour: \"{c}\" there", t.name),
            format!("do you mean a {} that is not {c}?", t.name),
        )
        .about_label(object_label(map, &t.name, pose));
        if !out.contains(&f) {
            out.push(f);
        }
    }
    out
}

/// Each colour word of the instruction as [`colour_mentions`] reads it (over the whole
/// instruction: "the ironing board, the white one" says white of the ironing board
/// across the comma), and whether a word that excludes ([`excludes`]) comes before it in
/// its clause ([`clauses`]; "a stretcher that isn't green": excluded).
/// Held-out v13 (dev since its third run) nb06: read within its clause, the white of
/// "then the ironing board, the white one, then the laundry basket in the lobby" was
/// said of no object, so the objects line's `(laundry basket, None, white)` beside a
/// right plan was a laundry basket the map lacks, and the re-asks lost the plan.
fn colour_mentions_excluded(
    map: &IvlMap,
    instruction: &str,
    pose: Pose,
) -> Vec<(String, Option<String>, bool)> {
    let mut excluded = Vec::new();
    for w in clauses(instruction) {
        let from = w.iter().position(|x| excludes(x));
        for i in (0..w.len()).filter(|&i| is_colour_word(&w[i])) {
            if normalise_colour(&w[i]).is_some() {
                excluded.push(from.is_some_and(|f| f < i));
            }
        }
    }
    // Both read the same colour words in the same order: clauses drop only punctuation
    // and the words that join them.
    colour_mentions(map, instruction, pose)
        .into_iter()
        .zip(excluded)
        .map(|((c, label), ex)| (c, label, ex))
        .collect()
}

/// The map labels that the instruction names only with a colour right before the name
/// ("the yellow table closest to the counter": table; [`noun_after`]'s reading), each
/// mention of them: not "the red chair, then another chair", nor "the sofa, the red
/// one" (a colour after its name).
pub(crate) fn labels_always_coloured(map: &IvlMap, instruction: &str, pose: Pose) -> Vec<String> {
    let w = words(instruction);
    // Each name a colour is said of, by where it begins.
    let coloured: Vec<(usize, String)> = (0..w.len())
        .filter(|&i| is_colour_word(&w[i]))
        .filter_map(|i| {
            let at = noun_index_after(&w, i);
            label_at(map, &w, at, pose).map(|(_, label, _)| (at, label))
        })
        .collect();
    let mut plain: Vec<String> = Vec::new();
    let mut j = 0;
    while j < w.len() {
        if is_colour_word(&w[j]) {
            j += 1;
            continue;
        }
        match label_at(map, &w, j, pose) {
            Some((_, l, len)) => {
                if !coloured.iter().any(|(at, c)| *at == j && *c == l) {
                    plain.push(l);
                }
                j += len;
            }
            None => j += 1,
        }
    }
    let mut out: Vec<String> = coloured
        .into_iter()
        .map(|(_, l)| l)
        .filter(|l| !plain.contains(l))
        .collect();
    out.sort();
    out.dedup();
    out
}

/// The map object a colour word at `i` is said of: the name right after it, past other
/// colour words ("the dark red sofa"), one or two words long ("coffee table"), if the map
/// holds it as an object (not a region). Post-noun colours ("the sofa, the red one",
/// "the chair painted red") have no name after them and are not judged here.
fn noun_after(map: &IvlMap, w: &[String], i: usize, pose: Pose) -> Option<(String, String)> {
    label_at(map, w, noun_index_after(w, i), pose).map(|(n, l, _)| (n, l))
}

/// The map object a colour word at `i` is said of: the name right after it
/// ([`noun_after`]: "the red sofa"), else, where the colour is followed by "one" and
/// preceded by "the" right after a name, that name (design.md: "the sofa, the red one"
/// is a colour filter on the sofa; held-out v9 and v10, dev, hw06 and kc06: "then the
/// swivel chair, the red one" was picked without red, and the re-ask, told of a red
/// said of no object, dropped it again). Not after a word between the name and "the"
/// ("the sofa, then the red one", "a chair other than the black one").
fn colour_noun(map: &IvlMap, w: &[String], i: usize, pose: Pose) -> Option<(String, String)> {
    noun_after(map, w, i, pose).or_else(|| {
        let the = i.checked_sub(1)?;
        (w.get(i + 1).map(String::as_str) == Some("one") && w[the] == "the")
            .then(|| noun_before_at(map, w, the, pose))
            .flatten()
    })
}

/// Where the name a colour word at `i` is said of begins: the first word after it past
/// other colour words and shades, at most three of them ([`noun_after`]).
fn noun_index_after(w: &[String], i: usize) -> usize {
    let mut j = i + 1;
    while j < w.len()
        && j <= i + 3
        && (is_colour_word(&w[j]) || matches!(w[j].as_str(), "dark" | "light" | "bright" | "pale"))
    {
        j += 1;
    }
    j
}

/// The map object (not a region) named by the words at `j`, two words ("coffee table")
/// before one: the words, its label and how many words it takes. Two words are a name
/// only where the matcher reads both: "the sack" is no name beginning at "the" (the
/// matcher drops a leading article, and "the sack" then named the hop sack where "the
/// sack truck" was said, and "the barrel" the oak barrel where "the barrel room" was:
/// held-out v12, dev, mb09).
fn label_at(map: &IvlMap, w: &[String], j: usize, pose: Pose) -> Option<(String, String, usize)> {
    let one = w.get(j)?;
    let mut candidates = Vec::new();
    if let Some(two) = w.get(j + 1) {
        let pair = format!("{one} {two}");
        if map_core::matcher::normalise(&pair) == pair {
            candidates.push((pair, 2));
        }
    }
    candidates.push((one.clone(), 1));
    candidates
        .into_iter()
        .find_map(|(n, len)| object_label(map, &n, pose).map(|l| (n, l, len)))
}

/// The map object a count at `i` is said of: the name after it past colour words (as
/// [`noun_after`]), else past one word more and its colour words ("the second nearest
/// chair", "the second closest black chair"), else a word
/// there that is a typo of an object's name ([`typed_label_at`]: "the second nearest
/// bycicle"). Held-out v3 (dev) hg14: with no name right after the count, any target
/// counted 2 (another object's) let "the second nearest bycicle" pass as the bicycle
/// nearest the stool.
fn count_noun(map: &IvlMap, w: &[String], i: usize, pose: Pose) -> Option<(String, String)> {
    let j = noun_index_after(w, i);
    let at = [j, noun_index_after(w, j)];
    let exact = at
        .iter()
        .find_map(|&k| label_at(map, w, k, pose).map(|(n, l, _)| (n, l)));
    exact.or_else(|| at.iter().find_map(|&k| typed_label_at(map, w, k)))
}

/// The map object (not a region) whose one-word name (a label or a synonym of one) the
/// word at `j` is a typo of: one edit away, two for names of six letters or more, the
/// word at least four letters long; `None` when none is, or when two labels are equally
/// close. The word and the label.
fn typed_label_at(map: &IvlMap, w: &[String], j: usize) -> Option<(String, String)> {
    let word = w.get(j)?;
    if word.chars().count() < 4 {
        return None;
    }
    let mut best: Option<(usize, String)> = None;
    let mut tied = false;
    for (label, _) in map.label_counts() {
        if is_region(map, &label) {
            continue;
        }
        for n in crate::v2::grammar::label_names(label.clone())
            .iter()
            .filter(|n| !n.contains(' '))
        {
            let d = strsim::damerau_levenshtein(word, n);
            if d > typo_limit(n, 6) {
                continue;
            }
            match &best {
                Some((bd, bl)) if *bd < d || (*bd == d && *bl == label) => {}
                Some((bd, _)) if *bd == d => tied = true,
                _ => {
                    best = Some((d, label.clone()));
                    tied = false;
                }
            }
        }
    }
    best.filter(|_| !tied).map(|(_, l)| (word.clone(), l))
}

/// Whether `name` is the name of one of the map's regions (rooms).
fn is_region(map: &IvlMap, name: &str) -> bool {
    map.regions.iter().any(|r| r.name == name)
}

/// The label of the map object `n` names, unless it names a region.
pub(crate) fn object_label(map: &IvlMap, n: &str, pose: Pose) -> Option<String> {
    let l = label_of(map, n, pose)?;
    (!is_region(map, &l)).then_some(l)
}

/// The map object named right before the word at `i` ("the desk furthest west"), one or
/// two words long, if the map holds it as an object (not a region): its label.
fn noun_before(map: &IvlMap, w: &[String], i: usize, pose: Pose) -> Option<String> {
    noun_before_at(map, w, i, pose).map(|(_, l)| l)
}

/// The map object a superlative at `i` ("farthest") is said of: named right before it
/// ("the desk farthest from you"), else right after it past colour words and one word
/// more ([`count_noun`]: "the farthest red desk", "the second farthest desk"), else the
/// last one named before it in its clause, up to six words back ("the bucket that's
/// second from farthest"); a clause ends at "then" and "and". Its label.
fn superlative_noun(map: &IvlMap, w: &[String], i: usize, pose: Pose) -> Option<String> {
    noun_before(map, w, i, pose)
        .or_else(|| count_noun(map, w, i, pose).map(|(_, l)| l))
        .or_else(|| {
            (i.saturating_sub(6)..i)
                .rev()
                .take_while(|&j| !matches!(w[j].as_str(), "then" | "and"))
                .find_map(|j| noun_before(map, w, j, pose))
        })
}

/// [`noun_before`] with the words of the name: the words, and the label.
fn noun_before_at(map: &IvlMap, w: &[String], i: usize, pose: Pose) -> Option<(String, String)> {
    let mut candidates = Vec::new();
    // Two words, unless the first is an article ("the chair" is the chair).
    if i >= 2 && !matches!(w[i - 2].as_str(), "the" | "a" | "an") {
        candidates.push(format!("{} {}", w[i - 2], w[i - 1]));
    }
    if i >= 1 {
        candidates.push(w[i - 1].clone());
    }
    candidates
        .into_iter()
        .find_map(|n| object_label(map, &n, pose).map(|l| (n, l)))
}

/// The instances the plan names by id (chat references).
fn plan_instances(plan: &TypedPlan) -> Vec<u32> {
    plan.steps
        .iter()
        .flat_map(Step::objects)
        .filter_map(|o| match o {
            planner_dsl::typed::Object::Instance(id) => Some(*id),
            _ => None,
        })
        .collect()
}

/// The instruction's words against the plan's targets. `visited`: the instances the dry
/// run stopped at; `picked`: every instance its selections picked, anchors included
/// ([`planner_dsl::RunOutcome::selected`]).
fn check_words(
    map: &IvlMap,
    instruction: &str,
    plan: &TypedPlan,
    pose: Pose,
    visited: &[u32],
    picked: &[u32],
) -> Vec<Finding> {
    let ts = targets(plan);
    let any_target = |f: &dyn Fn(&Target) -> bool| ts.iter().any(|t| f(t));
    let w = words(instruction);
    let mut out = Vec::new();
    // Words that belong to a name on the map ("red room") are not modifiers.
    let mut name_words: Vec<String> = map.regions.iter().flat_map(|r| words(&r.name)).collect();
    for (l, _) in map.label_counts() {
        name_words.extend(words(&l));
    }
    let mut said: Vec<String> = Vec::new();
    for (i, word) in w.iter().enumerate() {
        let prev = if i > 0 { w[i - 1].as_str() } else { "" };
        if word == "from" {
            out.extend(counted_from_a_side(&w, i, &any_target));
            continue;
        }
        // Colours.
        if is_colour_word(word) && !name_words.contains(word) {
            if let Some(c) = normalise_colour(word) {
                let repeated = said.contains(&c);
                said.push(c.clone());
                let reached = map
                    .instances
                    .iter()
                    .any(|i| visited.contains(&i.id) && same_colour(i.colour.as_deref(), &c));
                // Name the object it is said of, when the words say ("the second
                // black chair"): the re-ask then points at one selection.
                let of = colour_noun(map, &w, i, pose);
                // Or the plan picks one of that colour of the object it is said of, where
                // it makes no stop ("the saddle display next to the green frame jig" as
                // `near: get_obj("frame jig")`, on a map whose frame jig there is the
                // green one): what the plan does is what was asked. Held-out v16 (dev)
                // va05: that right first answer was re-asked.
                let picked_of = |label: &str| {
                    map.instances.iter().any(|i| {
                        picked.contains(&i.id)
                            && i.label == label
                            && same_colour(i.colour.as_deref(), &c)
                    })
                };
                let picked_here = of.as_ref().is_some_and(|(_, l)| picked_of(l));
                if !repeated
                    && !reached
                    && !picked_here
                    && !any_target(&|t| {
                        same_colour(t.colour.as_deref(), &c)
                            || same_colour(t.not_colour.as_deref(), &c)
                    })
                {
                    let to_model = match &of {
                        Some((noun, label)) => format!(
                            "the person said \"{word} {noun}\", but no {label} in the plan has colour \"{c}\": write colour: \"{c}\" in that {label}'s selection"
                        ),
                        None => format!("the person said \"{word}\", but no object in the plan has colour \"{c}\" (or not_colour \"{c}\")"),
                    };
                    // The question names the candidates: those of the object the colour
                    // is said of, else what on the map has that colour ("what is
                    // orange?" alone left the person to guess what was not understood).
                    let to_user = match &of {
                        Some((noun, label)) => format!(
                            "which {noun} is {word}? there are {}",
                            describe_label(map, label)
                        ),
                        None => format!("what is {word}? {}", describe_colour(map, &c, word)),
                    };
                    let mut f = Finding::new(FindingKind::Word, to_model, to_user);
                    if let Some((_, label)) = &of {
                        f = f.barring(Bar::ColourDropped {
                            label: label.clone(),
                        });
                    }
                    out.push(f);
                    continue;
                }
                // The colour on the object it is said of: "the chair next to the black
                // table" is a black table, not a black chair.
                if let Some((noun, label)) = of {
                    let of_label = picks(map, pose, &label);
                    // Excluded only where a word before says so ("not the red chair",
                    // "other than the red chair"): "the yellow table furthest from you"
                    // answered `#{ordinal: -1, not_colour: "yellow"}` (held-out v2's hf11,
                    // dev) is a yellow table, not any other.
                    let negated = w[i.saturating_sub(3)..i].iter().any(|x| excludes(x));
                    let carried = any_target(&|t| {
                        of_label(t)
                            && (same_colour(t.colour.as_deref(), &c)
                                || (negated && same_colour(t.not_colour.as_deref(), &c)))
                    });
                    let reached_here = map.instances.iter().any(|i| {
                        (visited.contains(&i.id)
                            || picked.contains(&i.id)
                            || plan_instances(plan).contains(&i.id))
                            && i.label == label
                            && same_colour(i.colour.as_deref(), &c)
                    });
                    if any_target(&of_label) && !carried && !reached_here {
                        out.push(
                            Finding::new(
                                FindingKind::Word,
                                format!("the person said \"{word} {noun}\", but no {label} in the plan has colour \"{c}\": the colour belongs to the {label}"),
                                format!(
                                    "is it the {noun} that is {word}? there are {}",
                                    describe_label(map, &label)
                                ),
                            )
                            .barring(Bar::ColourDropped { label: label.clone() }),
                        );
                    }
                }
            }
            continue;
        }
        // Superlatives of distance.
        if matches!(word.as_str(), "farthest" | "furthest") {
            // "furthest south": counted from that end, the first south-first or the last
            // north-first (Qwen 1.5B on held-out v2 wrote "the shelf furthest north" as
            // ordinal -1 in north_to_south, the southernmost, and a check that saw only
            // a direction let it pass).
            if let Some((j, o)) = side_after(&w, i) {
                let side = &w[j];
                // On the object it is said of, when that object's name comes right before
                // ("the desk furthest west"; held-out v2: another target's order let the
                // desk's wrong end pass).
                let of_noun =
                    said_and_picked(map, pose, noun_before(map, &w, i, pose), &any_target);
                let on_noun = on_said(map, pose, of_noun.as_deref());
                let counted = |t: &Target| from_end(t, o) && on_noun(t);
                if !any_target(&counted) {
                    let ordered = any_target(&|t| t.order == o || t.order == o.reversed());
                    let f = not_counted_from(&format!("{word} {side}"), o, ordered)
                        .about_label(of_noun.clone());
                    out.push(match ends_said_of_sides(&w) {
                        true => f.barring(Bar::CountFromStart),
                        false => f,
                    });
                }
                continue;
            }
            // From the far end: the last nearest-first, or the first farthest-first.
            // ordinal -1 in far_to_near is the nearest. On the object it is said of
            // ([`superlative_noun`]), where the plan picks that object; and after "from"
            // it names the end a count starts at ("the bucket that's second from
            // farthest": 2 far-to-near, as "from the westernmost" below). Held-out v16
            // (dev) vb04: `#{ordinal: 2}` (the second nearest) passed because another
            // object of the plan was counted far to near.
            let of_noun =
                said_and_picked(map, pose, superlative_noun(map, &w, i, pose), &any_target);
            let on_noun = on_said(map, pose, of_noun.as_deref());
            let count = from_before(&w, i)
                .and_then(|f| f.checked_sub(1))
                .and_then(|j| said_count(&w[j]).filter(|&k| k > 1).map(|k| (j, k)));
            if let Some((j, k)) = count {
                if !any_target(&|t| on_noun(t) && counts_from(t, ObjectOrder::FarToNear, k)) {
                    let said = w[j..=i].join(" ");
                    out.push(
                        Finding::new(
                            FindingKind::Word,
                            format!("the person said \"{said}\", but no object in the plan is counted so: that is ordinal: {k} with order \"far_to_near\" (or ordinal: -{k} alone)"),
                            format!("which one is the {said}?"),
                        )
                        .about_label(of_noun.clone()),
                    );
                }
                continue;
            }
            if !any_target(&|t| on_noun(t) && from_end(t, ObjectOrder::FarToNear)) {
                let to_model = if any_target(&|t| t.order == ObjectOrder::FarToNear) {
                    format!("the person said \"{word}\", but ordinal -1 in order \"far_to_near\" is the nearest: for the {word} write ordinal: -1 alone (or ordinal: 1 with order \"far_to_near\")")
                } else {
                    format!("the person said \"{word}\", but no object in the plan is counted from that end (ordinal -1, or an order)")
                };
                out.push(
                    Finding::new(
                        FindingKind::Word,
                        to_model,
                        format!("which one is the {word}?"),
                    )
                    .about_label(of_noun.clone()),
                );
            }
            continue;
        }
        // Size.
        let size = match word.as_str() {
            "biggest" | "largest" => Some(ObjectOrder::LargestToSmallest),
            "smallest" | "tiniest" => Some(ObjectOrder::SmallestToLargest),
            _ => None,
        };
        if let Some(o) = size {
            if !any_target(&|t| from_end(t, o)) {
                // ordinal -1 in largest_to_smallest is the smallest.
                out.push(not_counted_from(word, o, any_target(&|t| t.order == o)));
            }
            continue;
        }
        // Directional superlatives ("westernmost"): the first from that side, on the
        // object they are said of when its name follows and the plan picks it ("the
        // westernmost red shelf"). Held-out v4 (dev): "the westernmost shelf" as
        // `ordinal: -1, order: "west_to_east"` (the easternmost), and "treadmill number
        // 2, then the westernmost bike" as the second bike from the west, passed a check
        // that asked only for the order. "The second westernmost" is the second.
        if let Ok((Some(1), Some(order))) = parse_ordinal_with_order(word) {
            if let Ok(o) = ObjectOrder::parse(&order) {
                let of_noun = count_noun(map, &w, i, pose).map(|(_, l)| l);
                let of_noun = said_and_picked(map, pose, of_noun, &any_target);
                let on_noun = on_said(map, pose, of_noun.as_deref());
                let ordered = any_target(&|t| t.order == o || t.order == o.reversed());
                // After "from" it names the end a count starts at, as "from the west"
                // does: "the second display plinth counting from the westernmost one" is
                // a count in that order, whatever its number. Held-out v14 (dev) pb04:
                // read as "the westernmost" (ordinal 1), a right first answer
                // (`#{ordinal: 2, order: "west_to_east"}`) was re-asked, and the re-asks
                // ended in a refusal.
                if from_before(&w, i).is_some() {
                    if !any_target(&|t| on_noun(t) && from_end(t, o)) {
                        out.push(
                            Finding::new(
                                FindingKind::Word,
                                format!("the person counts from the {word} end, but no object in the plan is counted from there: write the count they said with order \"{order}\""),
                                format!("counting from the {word} one, which one do you mean?"),
                            )
                            .about_label(of_noun.clone()),
                        );
                    }
                    continue;
                }
                match said_count(prev).filter(|&k| k > 1) {
                    Some(k) if !any_target(&|t| on_noun(t) && counts_from(t, o, k)) => {
                        out.push(
                            Finding::new(
                                FindingKind::Word,
                                format!("the person said \"{prev} {word}\", but no object in the plan is counted so: that is ordinal: {k} with order \"{order}\""),
                                format!("which one is the {prev} {word}?"),
                            )
                            .about_label(of_noun.clone()),
                        );
                    }
                    None if !any_target(&|t| on_noun(t) && counts_from(t, o, 1)) => {
                        out.push(not_counted_from(word, o, ordered).about_label(of_noun.clone()));
                    }
                    _ => {}
                }
            }
            continue;
        }
        // Ordinals: "the third", "number 3", "no. 3", "#3"; "last".
        let counted =
            matches!(prev, "the" | "number" | "no" | "#") || (prev == "a" && word == "second");
        if counted && !name_words.contains(word) {
            // "penultimate" is -2 ([`said_count`]).
            let k = match parse_ordinal(word) {
                Ok(Some(k)) => Some(k),
                _ => said_count(word).filter(|&k| k == -2),
            };
            // "the second to last", "the next to last", "the last but one": counted from
            // the end ([`crate::tuples::count_from_the_end_at`]), its noun after those words.
            // Or one that ends here ("the one right before the last": held-out v16,
            // dev, vb08's right `ordinal: -2` was re-asked for the last).
            let phrase = crate::tuples::count_from_the_end_at(&w, i)
                .map(|(k, len)| (k, i..i + len))
                .or_else(|| {
                    let j = i.checked_sub(2)?;
                    crate::tuples::count_from_the_end_at(&w, j)
                        .filter(|&(_, len)| j + len == i + 1)
                        .map(|(k, len)| (k, j..j + len))
                });
            let to_last = phrase.is_some();
            let k = phrase.as_ref().map(|(k, _)| *k).or(k);
            let (said, at) = match phrase {
                Some((_, r)) => (w[r.clone()].join(" "), r.end - 1),
                None => (word.to_string(), i),
            };
            let word = said.as_str();
            if let Some(k) = k {
                // "the two tables" counts nothing: after "the", only ordinal forms
                // ("third", "3rd", "last"); after "number", any number.
                let ordinal_form = in_ordinal_form(word) || word == "last" || k == -2 || to_last;
                if (!matches!(prev, "number" | "no" | "#") && !ordinal_form) || k == 1 || k == 0 {
                    continue;
                }
                let last = k == -1;
                if last && word != "last" {
                    continue;
                }
                // From the end ("last", "penultimate"): -k, or k counted from the other
                // end of an order the person gave.
                // "The second chair you visited" counts the visits (`visited: 2`).
                let counts = |t: &Target| counts_as_said(t, k);
                let wanted = ordinal_wanted(k);
                // The object the count is said of ("the second chair"), when its name
                // follows, or, after "number", comes right before ("chair number 3,
                // then the plant": held-out v4 (dev) hk05 read the plant as counted):
                // the count must be on a target of that object.
                let before = match prev {
                    "number" | "no" | "#" => noun_before(map, &w, i - 1, pose),
                    _ => None,
                };
                let said_of = |noun: &str| match before {
                    Some(_) => format!("{noun} {prev} {word}"),
                    None => format!("{prev} {word} {noun}"),
                };
                let noun = match &before {
                    Some(l) => Some((l.clone(), l.clone())),
                    // "The last pottery wheel but one": the name is inside the words.
                    None if word.starts_with("last ") && !word.starts_with("last but") => {
                        count_noun(map, &w, i, pose)
                    }
                    None => count_noun(map, &w, at, pose),
                };
                if !any_target(&counts) {
                    let of = noun
                        .as_ref()
                        .map_or("object".to_string(), |(_, l)| l.clone());
                    // The question names the candidates when the object is known.
                    let to_user = match &noun {
                        Some((n, l)) => format!(
                            "which {n} is the {word}? there are {}",
                            describe_label(map, l)
                        ),
                        None => format!("which one is the {word}?"),
                    };
                    out.push(
                        Finding::new(
                            FindingKind::Word,
                            format!("the person said \"{prev} {word}\", but no {of} in the plan has ordinal {wanted}"),
                            to_user,
                        )
                        .about_label(noun.as_ref().map(|(_, l)| l.clone())),
                    );
                } else if let Some((noun, label)) = noun {
                    let of_label = picks(map, pose, &label);
                    if any_target(&of_label) && !any_target(&|t| of_label(t) && counts(t)) {
                        out.push(
                            Finding::new(
                                FindingKind::Word,
                                format!("the person said \"{}\", but no {label} in the plan has ordinal {wanted}: the count belongs to the {label}", said_of(&noun)),
                                format!(
                                    "which {noun} is the {word}? there are {}",
                                    describe_label(map, &label)
                                ),
                            )
                            .about_label(Some(label.clone())),
                        );
                    }
                }
            }
        }
    }
    out
}

/// Where "from" is said right before `w[i]`, or before "the" right before it ("second
/// from farthest", "counting from the westernmost one"): the word then names the end a
/// count starts at.
fn from_before(w: &[String], i: usize) -> Option<usize> {
    let at = |j: usize| w.get(j).map(String::as_str);
    match at(i.checked_sub(1)?)? {
        "from" => Some(i - 1),
        "the" if at(i.checked_sub(2)?) == Some("from") => Some(i - 2),
        _ => None,
    }
}

/// How many words before "from the west" its count may be said ("the second to last
/// red plant from the west": five).
const FROM_WORDS: usize = 5;

/// Whether `word` counts from the end ("last", "furthest", "penultimate"): a count
/// "from the west" with it starts at the east.
fn counts_from_the_end(word: &str) -> bool {
    matches!(word, "last" | "furthest" | "farthest") || said_count(word) == Some(-2)
}

/// Whether some target of the plan passes a test.
type AnyTarget<'a> = dyn Fn(&dyn Fn(&Target) -> bool) -> bool + 'a;

/// A count said from a side, as [`side_count`] reads it.
struct SideCount {
    /// The order it counts in: starting at the side, or at the other side where a count
    /// from the end is said.
    order: ObjectOrder,
    /// The count (1 where none is written: "the last ... from the west").
    k: i64,
    /// Whether a count from the end is said ("last", "to last", "penultimate").
    from_the_end: bool,
    /// The words that say it.
    span: std::ops::Range<usize>,
}

/// The count said from a side at `w[at]` ("from"; [`counted_from_a_side`]): `None`
/// where no side follows "from the", or no count is said within [`FROM_WORDS`] words
/// before it (or after it, after "counting").
fn side_count(w: &[String], at: usize) -> Option<SideCount> {
    let (Some("the"), Some(side)) = (w.get(at + 1).map(String::as_str), w.get(at + 2)) else {
        return None;
    };
    let start = ObjectOrder::starting_at(side)?;
    // "One" is the pronoun here, not a count: "counting from the north, the cabinet one
    // before the end" says no first (held-out v15, dev: "the one before the final one").
    let is_count = |x: &String| x != "one" && (counts_from_the_end(x) || said_count(x).is_some());
    let before = at.saturating_sub(FROM_WORDS)..at;
    let counting = at > 0 && w[at - 1].starts_with("count");
    let span = match w[before.clone()].iter().position(is_count) {
        Some(p) => before.start + p..at + 3,
        None if counting => {
            let p = w
                .iter()
                .skip(at + 3)
                .take(FROM_WORDS + 1)
                .position(is_count)?;
            at - 1..at + 4 + p
        }
        None => return None,
    };
    // A count from the end in more than one word may begin before the window: "the
    // second from last dog kennel counting from the west" (held-out v11, dev, lc09: read
    // as "last ... from the west", ordinal 1, a right plan was re-asked), "the
    // last-but-one ball return counting from the west" (v12, dev, ma09: read as "one").
    let phrase = counts_in(w)
        .into_iter()
        .find(|(k, r)| *k < 0 && r.len() > 1 && r.start < span.end && r.end > span.start);
    let (span, from_the_end, k) = match phrase {
        Some((k, r)) => (span.start.min(r.start)..span.end.max(r.end), true, -k),
        None => {
            let said = &w[span.clone()];
            let k = said
                .iter()
                .filter_map(|x| said_count(x))
                .map(i64::abs)
                .find(|&k| k > 1)
                .unwrap_or(1);
            (span, said.iter().any(|x| counts_from_the_end(x)), k)
        }
    };
    let order = if from_the_end {
        start.reversed()
    } else {
        start
    };
    Some(SideCount {
        order,
        k,
        from_the_end,
        span,
    })
}

/// A count said from a side (`w[at]` is "from"): "the second plant from the west" is
/// ordinal 2 in `west_to_east`, and "the second to last plant from the west" ordinal 2
/// in `east_to_west` (design.md). The count is said within [`FROM_WORDS`] words before
/// "from", or after it where the words are "counting from the west, ...". A finding
/// when no target is counted from that end (either sign: -k in the reverse is the same
/// object). Held-out v3 (dev): "the second red chair counting from the west" was
/// counted from the east and no check saw it.
fn counted_from_a_side(w: &[String], at: usize, any_target: &AnyTarget<'_>) -> Vec<Finding> {
    let Some(SideCount {
        order: o, k, span, ..
    }) = side_count(w, at)
    else {
        return Vec::new();
    };
    // An unwritten ordinal is the first (map_core), so it counts only "the first ...
    // from the east" (held-out v7, dev, hq14: `#{order: "east_to_west"}` was re-asked).
    if any_target(&|t| (t.ordinal != 0 || k == 1) && from_end(t, o)) {
        return Vec::new();
    }
    let words = &w[span];
    let said = words.join(" ");
    vec![Finding::new(
        FindingKind::Word,
        format!(
            "the person said \"{said}\": that is ordinal: {k} with order \"{}\", and no object in the plan is counted so",
            o.name()
        ),
        format!("which one is the {said}?"),
    )]
}

/// Whether every count from the end that `w` says ([`counts_from_the_end`]: "last",
/// "furthest", "penultimate") is "furthest" (or "farthest") before a side ([`side_after`]: "the
/// shelf furthest north"): a positive count in the order starting at that side says
/// each ([`Bar::CountFromStart`]). "The farthest bin", "the last chair", "the most
/// distant chair" ([`speaks_of_the_far_end`], as [`far_end_said`] reads it) and "the
/// second to last shelf from the west" (`ordinal: -2, order: "west_to_east"`) count from
/// an end.
pub(crate) fn ends_said_of_sides(w: &[String]) -> bool {
    w.iter().enumerate().all(|(j, x)| {
        !(counts_from_the_end(x) || speaks_of_the_far_end(x))
            || (matches!(x.as_str(), "furthest" | "farthest") && side_after(w, j).is_some())
    })
}

/// The side that "furthest" at `i` counts from, and where it is said: a side named in
/// the four words after it ("the shelf furthest north", "the white microscope furthest
/// to the east", "the tandem furthest along to the east": held-out v16, dev, va02, read
/// as the far end with three), before any "from", "then" or "and" ("the chair furthest from you on the
/// left" counts from the robot). Held-out v8 (dev since its third run) hr11: with only
/// the next word read, "furthest to the east" answered `#{colour: "white", order:
/// "east_to_west"}` (the easternmost, right) was re-asked for a far end and ended in a
/// question.
fn side_after(w: &[String], i: usize) -> Option<(usize, ObjectOrder)> {
    w.iter()
        .enumerate()
        .skip(i + 1)
        .take(4)
        .take_while(|(_, x)| !matches!(x.as_str(), "from" | "then" | "and"))
        .find_map(|(j, x)| ObjectOrder::starting_at(x).map(|o| (j, o)))
}

/// Whether the person counts from an end only as "furthest" + a side, and says one
/// ("the shelf furthest north, then the red chair", [`ends_said_of_sides`]): each such
/// count is a positive one in the order starting at that side, and none counts from the
/// robot, so a first answer is offered what a re-ask after a "furthest" + side finding
/// is ([`Bar::CountFromStart`]), and no `far_to_near`.
pub(crate) fn only_sides_counted_from_the_end(instruction: &str) -> bool {
    let w = words(instruction);
    ends_said_of_sides(&w)
        && w.iter()
            .any(|x| matches!(x.as_str(), "furthest" | "farthest"))
}

/// The finding for a superlative (`said`: "biggest", "furthest west") that no target
/// counts from the start of `o`; `ordered`: some target is counted in `o` or its reverse,
/// from the other end.
fn not_counted_from(said: &str, o: ObjectOrder, ordered: bool) -> Finding {
    let to_model = if ordered {
        format!("the person said \"{said}\", but the plan counts order \"{}\" from the other end: for the {said} write ordinal: 1 with order \"{}\"", o.name(), o.name())
    } else {
        format!(
            "the person said \"{said}\", but no object in the plan is counted in the order \"{}\": for the {said} write ordinal: 1 with order \"{}\"",
            o.name(),
            o.name()
        )
    };
    Finding::new(
        FindingKind::Word,
        to_model,
        format!("which one is the {said}?"),
    )
}

/// Whether `t` is the `k`-th from the start of `order` ("the westernmost": 1 in
/// `west_to_east`, -1 in `east_to_west`; an unspecified ordinal is the first).
fn counts_from(t: &Target, order: ObjectOrder, k: i64) -> bool {
    let ordinal = if t.ordinal == 0 { 1 } else { t.ordinal };
    (t.order == order && ordinal == k) || (t.order == order.reversed() && ordinal == -k)
}

/// Whether `t` counts from the start of `order` ("the biggest": the first
/// largest-first, or the last smallest-first; "the second biggest" likewise): a positive
/// (or unspecified) ordinal in `order`, or a negative one in its reverse.
fn from_end(t: &Target, order: ObjectOrder) -> bool {
    (t.order == order && t.ordinal >= 0) || (t.order == order.reversed() && t.ordinal < 0)
}

/// The names the map holds that the person said, in order, once each: a label or a
/// region, one or two words ("coffee table", "living room"), or the plural of its last
/// word ("the two tables"). A two-word name takes its words: "coffee table" is not also
/// a "table". Synonyms ("couch") are not read here, so they are never judged.
fn said_names(map: &IvlMap, w: &[String]) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    for (i, len, name) in names_at(map, w) {
        if !out.iter().any(|(_, l)| *l == name) {
            out.push((w[i..i + len].join(" "), name));
        }
    }
    out
}

/// Each map name (label or region) the words `w` say, as [`said_names`] reads them, each
/// time: where it begins, how many words it takes, the name.
fn names_at(map: &IvlMap, w: &[String]) -> Vec<(usize, usize, String)> {
    let names: Vec<(String, Vec<String>)> = names_on_map(map)
        .into_iter()
        .map(|n| {
            let ws = words(&n);
            (n, ws)
        })
        .filter(|(_, ws)| !ws.is_empty())
        .collect();
    let matches = |at: usize, ws: &[String]| {
        let n = ws.len();
        at + n <= w.len()
            && w[at..at + n - 1] == ws[..n - 1]
            && (w[at + n - 1] == ws[n - 1]
                || w[at + n - 1] == map_core::matcher::plural(&ws[n - 1]))
    };
    let mut out = Vec::new();
    let mut i = 0;
    while i < w.len() {
        let best = names
            .iter()
            .filter(|(_, ws)| matches(i, ws))
            .max_by_key(|(_, ws)| ws.len());
        match best {
            Some((name, ws)) => {
                out.push((i, ws.len(), name.clone()));
                i += ws.len();
            }
            None => i += 1,
        }
    }
    out
}

/// Every map name the instruction's words `w` say, in order, each time, with the word
/// where it begins: the names and rooms of [`names_at`], and the objects' synonyms where
/// no name is ([`label_at`]: "telly" is the tv).
pub(crate) fn name_mentions(map: &IvlMap, w: &[String], pose: Pose) -> Vec<(usize, String)> {
    name_mentions_with_len(map, w, pose)
        .into_iter()
        .map(|(k, _, name)| (k, name))
        .collect()
}

/// The words of [`name_mentions`]: where each begins and how many words it takes.
fn name_spans(map: &IvlMap, w: &[String], pose: Pose) -> Vec<(usize, usize)> {
    name_mentions_with_len(map, w, pose)
        .into_iter()
        .map(|(k, len, _)| (k, len))
        .collect()
}

fn name_mentions_with_len(map: &IvlMap, w: &[String], pose: Pose) -> Vec<(usize, usize, String)> {
    let exact = names_at(map, w);
    let mut out = Vec::new();
    let mut k = 0;
    while k < w.len() {
        if let Some((_, len, name)) = exact.iter().find(|(i, _, _)| *i == k) {
            out.push((k, *len, name.clone()));
            k += len;
        } else if let Some((_, label, len)) = label_at(map, w, k, pose) {
            out.push((k, len, label));
            k += len;
        } else {
            k += 1;
        }
    }
    out
}

/// The room the robot is in (at `pose`) where it is the first name the person says
/// ([`name_mentions`]): "Starting from lost property: the lamp post furthest from you,
/// ..." says where the robot is, and a room it is already in is no stop to make.
/// Held-out v10 (dev since its third run) kb14: a right stop list was re-asked for
/// "lost property", and the re-asks lost it. Named after an object ("the chair in the
/// kitchen") it is where that object is, and judged as before.
fn start_room_named_first(map: &IvlMap, w: &[String], pose: Pose) -> Option<String> {
    let (_, first) = name_mentions(map, w, pose).into_iter().next()?;
    map.regions
        .iter()
        .any(|r| r.name == first && r.polygon.contains(pose.position))
        .then_some(first)
}

/// Every name the person said that the plan leaves out: no target, bare name, region or
/// referred instance of it, and the dry run stops at none ("go to the red sofa" answered
/// with a bathtub).
fn check_names(
    map: &IvlMap,
    instruction: &str,
    plan: &TypedPlan,
    pose: Pose,
    visited: &[u32],
    refs: &[u32],
) -> Vec<Finding> {
    let accounts = Accounts::new(map, instruction, plan, pose);
    let by_position = plan.steps.iter().any(|s| matches!(s, Step::MoveTo(_)));
    let w = words(instruction);
    let mut out = Vec::new();
    for (said, label) in said_names(map, &w) {
        // "go back to the sofa you visited" may be a move to where the robot stopped.
        if !accounts.has(map, &label, visited, by_position.then_some(refs)) {
            // A room is not picked with get_obj (the grammar offers only object names
            // there): measured on held-out v2 (dev), asked to pick "the restroom" with
            // get_obj, the default model wrote get_obj("refrigerator").
            let is_room = is_region(map, &label) && !map.instances.iter().any(|i| i.label == label);
            let to_model = if is_room {
                format!("the person said \"{said}\", a room, but the plan neither goes into the {label} nor picks an object in it: go there with move_to_object(\"{label}\"), or give the object in it region: \"{label}\"")
            } else {
                format!("the person said \"{said}\", but the plan neither goes to nor uses a {label}: pick it with get_obj(\"{label}\", ...) where the person wants it")
            };
            let f = Finding::new(
                FindingKind::Word,
                to_model,
                format!("what should I do with the {said}?"),
            );
            out.push(f.missing(label));
        }
    }
    out
}

/// Colours in the plan that the person never said: a target's `colour` or `not_colour`
/// that no word of the instruction names, with the field's name. `known` holds the
/// colours the conversation told the model ("the other one" after the red sofa is not
/// red). No worked example may have one.
pub(crate) fn unsaid_colours<'a>(
    instruction: &str,
    known: &[String],
    plan: &'a TypedPlan,
) -> Vec<(&'a Target, &'static str, &'a str)> {
    let is_said = colour_said(instruction, known);
    let mut out = Vec::new();
    for t in targets(plan) {
        for (field, c) in [("colour", &t.colour), ("not_colour", &t.not_colour)] {
            if let Some(c) = c.as_deref().filter(|c| !is_said(c)) {
                out.push((t, field, c));
            }
        }
    }
    out
}

/// The words that count as said for what a plan may select on: `instruction`'s, after
/// those of the `earlier` instruction it may answer ([`check_answer_after`]).
pub(crate) fn said_before(instruction: &str, earlier: Option<&str>) -> String {
    match earlier {
        Some(e) => format!("{e}\n{instruction}"),
        None => instruction.to_string(),
    }
}

/// The colours that count as said besides the instruction's own words: those of the
/// instances `refs` (what the conversation visited), and the colour words of the
/// `earlier` instruction this one may answer ([`check_answer_after`]).
pub(crate) fn known_colours(map: &IvlMap, refs: &[u32], earlier: Option<&str>) -> Vec<String> {
    let mut known = colours_of(map, refs);
    if let Some(e) = earlier {
        known.extend(words(e).into_iter().filter_map(|w| normalise_colour(&w)));
    }
    known
}

/// The colours of the instances `refs` (what the conversation visited), which count as
/// said ([`colour_said`]'s `known`).
pub(crate) fn colours_of(map: &IvlMap, refs: &[u32]) -> Vec<String> {
    refs.iter()
        .filter_map(|id| map.instance_by_id(*id))
        .filter_map(|i| i.colour.clone())
        .collect()
}

/// Whether a colour is said by `instruction` or is one of the `known` colours (of what
/// the conversation visited): a colour word of the instruction, a typed one ("blak")
/// counting as the colour it is one or two edits from ([`typed_as_colour`]), grey as
/// gray.
pub(crate) fn colour_said<'a>(
    instruction: &str,
    known: &'a [String],
) -> impl Fn(&str) -> bool + 'a {
    let said: Vec<String> = words(instruction)
        .iter()
        .chain(known)
        .filter_map(|w| normalise_colour(w))
        .map(|c| canonical(&c))
        .collect();
    let close = move |c: &str| said.iter().any(|s| typed_as_colour(s, c));
    move |c: &str| close(&canonical(c)) || words(c).iter().any(|w| close(&canonical(w)))
}

/// Whether the said word `s` is the colour `c` or a typo of it: one edit (two for a
/// colour of six letters or more), the first letter kept (a typist rarely gets the first
/// letter wrong), and for a colour of three letters only two letters swapped ("rde").
/// Held-out v11 (dev) la09: with any one edit, "camp bed" said red, and the re-ask's
/// `#{ordinal: 2, colour: "red", order: "east_to_west"}` for "the second-to-last hose
/// reel from the west" passed as a said colour, a wrong stop. Read so before this,
/// "than", "van", "can" and "tank" said tan, "sink" pink and "cold" gold. The everyday
/// words of [`EVERYDAY_NEAR_COLOURS`] are not typos.
fn typed_as_colour(s: &str, c: &str) -> bool {
    if s == c {
        return true;
    }
    if EVERYDAY_NEAR_COLOURS.contains(&s) || s.chars().next() != c.chars().next() {
        return false;
    }
    if c.chars().count() <= 3 {
        return s.chars().count() == c.chars().count()
            && strsim::damerau_levenshtein(s, c) == 1
            && strsim::levenshtein(s, c) == 2;
    }
    strsim::damerau_levenshtein(s, c) <= typo_limit(c, 6)
}

/// Everyday words one edit from a colour word, first letter kept, which
/// [`typed_as_colour`] does not read as typos of it (as `said_count` leaves "there" for
/// "three"): every such word of the instructions of the suites v2 to v15, counted over
/// them: "back" (black, 277 times: "come back to me"), "can" (cyan, 43), "tea" (teal, 8),
/// "good" (gold, 6), "server" (silver, 4), "pick" (pink, 1). Held-out v15 (dev since its
/// third run) rb03: "..., then the poster rack, then the pay terminal, and next pop back
/// to me" offered the poster rack black, and the plan went to the black one, not the
/// nearest.
const EVERYDAY_NEAR_COLOURS: &[&str] = &["back", "can", "tea", "good", "server", "pick"];

/// Whether one of the `said` words is `word` or a typo of it: one edit from it, two for
/// a `word` of `long` letters or more.
fn typed_as(said: &[String], word: &str, long: usize) -> bool {
    let limit = typo_limit(word, long);
    said.iter()
        .any(|s| s == word || strsim::damerau_levenshtein(s, word) <= limit)
}

/// How many edits a typo of `word` may be: one, two for a word of `long` letters or more.
fn typo_limit(word: &str, long: usize) -> usize {
    if word.chars().count() < long {
        1
    } else {
        2
    }
}

/// Whether a region (a room) is named by `instruction`: every word of the region's name,
/// or of one of its synonyms ("lounge" for the living room), is a word of the
/// instruction, a typed one ("kitchn", "libary") counting as the word it is one edit
/// from (two for words of eight letters or more: "dining" is not "living"). A word of
/// `exact` (the words of the map's object names, [`object_name_words`]) is read only as
/// itself: "the display case" names no cafe (held-out v7, dev, ho11: with "cafe" on
/// offer, "then the counter" was answered `#{region: "cafe"}`).
pub(crate) fn region_said(instruction: &str, exact: &[String]) -> impl Fn(&str) -> bool {
    let (exact_words, typed): (Vec<String>, Vec<String>) = words(instruction)
        .into_iter()
        .partition(|w| exact.contains(w));
    move |region: &str| {
        let close = |w: &str| exact_words.iter().any(|x| x == w) || typed_as(&typed, w, 8);
        let mut names: Vec<String> = map_core::matcher::synonyms(region)
            .into_iter()
            .map(str::to_string)
            .collect();
        names.push(region.to_string());
        names.iter().any(|n| {
            let ws = words(n);
            !ws.is_empty() && ws.iter().all(|w| close(w))
        })
    }
}

/// Targets selected in a region the person did not name ([`region_said`]): "the lamp"
/// answered with `#{region: "bathroom"}` after "the sink in the bathroom", or with a
/// room nobody said. A region narrows what is picked, so it is the person's to say. In a
/// conversation (`in_chat`) regions are not judged: the room may have been said before.
/// No worked example may have one.
pub(crate) fn unsaid_regions<'a>(
    instruction: &str,
    exact: &[String],
    in_chat: bool,
    plan: &'a TypedPlan,
) -> Vec<&'a Target> {
    if in_chat {
        return Vec::new();
    }
    let said = region_said(instruction, exact);
    targets(plan)
        .into_iter()
        .filter(|t| t.region.as_deref().is_some_and(|r| !said(r)))
        .collect()
}

/// Whether `instruction` asks the robot to come back to where it began (design.md:
/// "come back here", "back to where you started", and in a conversation "where we
/// started"): "back here", "come back" (or "go back", "head back", "get back") that
/// ends its clause, "where you / we started" (began), "to the start" (starting point,
/// beginning), "return" that ends its clause or goes "here". "Go back to the table"
/// is not one: it names where to go.
pub(crate) fn return_said(instruction: &str) -> bool {
    // Clauses end at punctuation and at the words that join two requests.
    let lower = instruction.to_lowercase();
    let mut toks: Vec<&str> = Vec::new();
    const ENDS: [char; 5] = [',', '.', ';', '!', '?'];
    for piece in lower.split_inclusive(ENDS) {
        toks.extend(
            piece
                .split(|c: char| !(c.is_alphanumeric() || c == '\''))
                .filter(|w| !w.is_empty()),
        );
        if piece.ends_with(ENDS) {
            toks.push(",");
        }
    }
    let ends_clause = |i: usize| {
        toks.get(i).is_none_or(|w| {
            matches!(
                *w,
                "," | "and"
                    | "then"
                    | "please"
                    | "pls"
                    | "plz"
                    | "again"
                    | "now"
                    | "after"
                    | "afterwards"
                    | "when"
                    | "once"
                    | "thanks"
                    | "thx"
                    | "here"
                    | "home"
            )
        })
    };
    let moving = |i: usize| {
        i.checked_sub(1).and_then(|j| toks.get(j)).is_some_and(|p| {
            matches!(
                *p,
                "come" | "coming" | "go" | "going" | "head" | "get" | "drive" | "walk" | "move"
            )
        })
    };
    toks.iter().enumerate().any(|(i, w)| {
        let next = toks.get(i + 1).copied();
        match *w {
            "back" => next == Some("here") || (moving(i) && ends_clause(i + 1)),
            "return" | "returning" => ends_clause(i + 1),
            "where" => {
                matches!(next, Some("you" | "we" | "u" | "i" | "ya"))
                    && toks.get(i + 2).is_some_and(|v| {
                        matches!(*v, "started" | "start" | "began" | "begun" | "begin")
                    })
            }
            "to" => {
                let k = match next {
                    Some("the" | "your" | "our" | "my" | "ur") => i + 2,
                    _ => i + 1,
                };
                toks.get(k)
                    .is_some_and(|v| matches!(*v, "start" | "starting" | "beginning"))
            }
            _ => false,
        }
    })
}

/// Whether `instruction` asks the robot to come back to where it began, read with the
/// map: [`return_said`], or a clause ([`clauses`]) with "back", "return" or "home" that
/// is no part of a map name, no noun ("the back of the hall": after an article), and
/// whose words after it name nothing of the map (no object, room or synonym of one,
/// [`name_spans`]) and no distance (no digit, no number word before a unit: "first" and
/// "square one" are no distance, and typos of count words are not read, "right" is no
/// "eight") and no word that refers back ([`refers_back_at`]): where a person sends the
/// robot back and names no place, the place is where it began. "Go back to the table you
/// just visited" names the table; "back up 2 metres" is a distance.
/// Held-out v13 (dev since its third run): "Once that's done, loop back to me" (na01),
/// "then come back to the position you're in right now" (nc01) and "then return to your
/// origin point" (nc03) were read as no return, and each plan ended without one. Read
/// from the map's names rather than from a list of the ways to say the start.
/// In a conversation (`in_chat`) only [`return_said`]: there "go back there" and "back to
/// it" mean a place visited before.
pub(crate) fn return_said_on(map: &IvlMap, instruction: &str, pose: Pose, in_chat: bool) -> bool {
    if return_said(instruction) {
        return true;
    }
    if in_chat {
        return false;
    }
    clauses(instruction).iter().any(|c| {
        let spans = name_spans(map, c, pose);
        let in_name = |i: usize| spans.iter().any(|&(a, n)| (a..a + n).contains(&i));
        // "the back of the hall": a noun, after an article.
        let a_noun = |i: usize| {
            i.checked_sub(1)
                .is_some_and(|p| matches!(c[p].as_str(), "the" | "a" | "its" | "their"))
        };
        let names_after = |i: usize| spans.iter().any(|&(a, _)| a > i);
        // "come over to me again", "finish next to me": the person, who stands where
        // the robot began (design.md's "come back here" said of the speaker). Held-out
        // v16 (dev) va01: "once ur done come over to me again" was read as no return.
        // Only in a clause that names nothing of the map: "the sofa next to me" names
        // the sofa.
        // "come find me here" (v15, dev, ra01) likewise.
        let to_me = |i: usize| {
            c[i] == "me"
                && spans.is_empty()
                && (i.checked_sub(1).is_some_and(|p| {
                    matches!(
                        c[p].as_str(),
                        "to" | "by" | "beside" | "near" | "towards" | "toward"
                    )
                }) || c.get(i + 1).is_some_and(|x| x == "here"))
        };
        c.iter().enumerate().any(|(i, w)| {
            (matches!(w.as_str(), "back" | "return" | "returning" | "home") || to_me(i))
                && !in_name(i)
                && !a_noun(i)
                && !names_after(i)
                && !(i + 1..c.len()).any(|j| {
                    c[j].chars().any(|ch| ch.is_ascii_digit())
                        || distance_at(c, j)
                        || refers_back_at(c, j)
                })
        })
    })
}

/// Units of a distance said in words ("go back three metres"), read by [`distance_at`].
const DISTANCE_UNITS: &[&str] = &[
    "m", "metre", "metres", "meter", "meters", "cm", "ft", "foot", "feet", "yard", "yards", "step",
    "steps",
];

/// Whether `w[j]` refers to something said or seen before ("back to it", "back there",
/// "back to the one you saw"): no start.
fn refers_back_at(w: &[String], j: usize) -> bool {
    match w[j].as_str() {
        "it" | "there" => true,
        "one" => j > 0 && matches!(w[j - 1].as_str(), "the" | "that" | "this"),
        _ => false,
    }
}

/// Whether `w[j]` is a number said before a unit of distance ([`DISTANCE_UNITS`]).
fn distance_at(w: &[String], j: usize) -> bool {
    matches!(parse_ordinal(&w[j]), Ok(Some(k)) if k >= 1)
        && w.get(j + 1)
            .is_some_and(|u| DISTANCE_UNITS.contains(&u.as_str()))
}

/// An instance as the conversation's references name it: "chair 9 (red)".
pub(crate) fn instance_words(i: &map_core::Instance) -> String {
    format!(
        "{} {} ({})",
        i.label,
        i.id,
        i.colour.as_deref().unwrap_or("unknown colour")
    )
}

/// What a chat reference says of the object it means: visited earlier ("the bench you
/// visited first", "that same chair", "the chair again") or not ("the other counter",
/// "the lamp you haven't been to yet").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Visit {
    Earlier,
    NotYet,
}

/// The chat references in `instruction`: each with the words that make it, what it says
/// of the visits and the map label it is said of (`None`: "one", "the other one").
/// Only references whose object is named or is "one": "the other side", "the kitchen
/// again" refer to no visited object.
fn visit_references(
    map: &IvlMap,
    instruction: &str,
    pose: Pose,
) -> Vec<(String, Visit, Option<String>)> {
    let w = words(instruction);
    let at = |i: usize| w.get(i).map_or("", String::as_str);
    let one_at = |i: usize| matches!(at(i), "one" | "ones");
    let mut out = Vec::new();
    let mut push = |said: String, v: Visit, label: Option<String>, one: bool| {
        // once each: "the same chair again" is one reference
        if (label.is_some() || one) && !out.iter().any(|(_, w, l)| *w == v && *l == label) {
            out.push((said, v, label));
        }
    };
    for (i, word) in w.iter().enumerate() {
        let before = |n: usize| &w[i.saturating_sub(n)..i];
        match word.as_str() {
            "other" | "another" | "different" | "remaining" | "same" | "previous" => {
                let v = if matches!(word.as_str(), "same" | "previous") {
                    Visit::Earlier
                } else {
                    Visit::NotYet
                };
                let label = noun_after(map, &w, i, pose).map(|(_, l)| l);
                let one = (i + 1..(i + 4).min(w.len())).any(one_at);
                push(format!("{word} {}", at(i + 1)), v, label, one);
            }
            "again" => {
                let label = noun_before(map, &w, i, pose);
                push(
                    format!("{} again", at(i.wrapping_sub(1))),
                    Visit::Earlier,
                    label,
                    i > 0 && one_at(i - 1),
                );
            }
            "visited" | "been" | "went" | "gone" | "were" | "skipped" | "tried" => {
                // "you were at", "you went to": a place after the verb.
                if matches!(word.as_str(), "were" | "went" | "gone" | "been")
                    && !matches!(at(i + 1), "to" | "at" | "by" | "past")
                {
                    continue;
                }
                // The subject right before ("you", "u", "we", after a "havent"), and the
                // object named before it: "the bench you visited first".
                let Some(subject) = before(3)
                    .iter()
                    .rposition(|x| matches!(x.as_str(), "you" | "u" | "we" | "ya"))
                    .map(|k| i.saturating_sub(3) + k)
                else {
                    continue;
                };
                let negated = word == "skipped"
                    || w[subject..i].iter().any(|x| {
                        matches!(
                            x.as_str(),
                            "haven't"
                                | "havent"
                                | "have"
                                | "not"
                                | "never"
                                | "didn't"
                                | "didnt"
                                | "did"
                                | "hadn't"
                                | "hadnt"
                        )
                    });
                let label = noun_before(map, &w, subject, pose);
                let one = subject > 0 && one_at(subject - 1);
                let v = if negated {
                    Visit::NotYet
                } else {
                    Visit::Earlier
                };
                push(w[subject..=i].join(" "), v, label, one);
            }
            _ => {}
        }
    }
    out
}

/// Chat references against the plan's stops (`stops`: the dry run's objects, in order)
/// and the conversation's earlier visits (`refs`): "the X you visited" with no stop at a
/// visited X, "the other X" with every stop at an X visited before. Measured on held-out
/// v5 (read after its run, untuned no more): "back to the bench you visited first" as
/// the nearest bench, "other counter now pls" as the counter just visited, "the table you
/// havent visited yet" as a visited table; each a silent wrong plan.
fn check_visits(
    map: &IvlMap,
    instruction: &str,
    pose: Pose,
    stops: &[u32],
    refs: &[u32],
) -> Vec<Finding> {
    // Only with the dry run's stops: without them nothing says where the plan goes.
    if refs.is_empty() || stops.is_empty() {
        return Vec::new();
    }
    let label_of_id = |id: u32| map.instance_by_id(id).map(|i| i.label.clone());
    let of = |id: &u32, label: &Option<String>| {
        label.is_none() || label_of_id(*id).as_ref() == label.as_ref()
    };
    let visited_of = |label: &Option<String>| -> String {
        let ids: Vec<String> = refs
            .iter()
            .filter(|id| of(id, label))
            .filter_map(|id| map.instance_by_id(*id).map(instance_words))
            .collect();
        if ids.is_empty() {
            "none".to_string()
        } else {
            ids.join(", ")
        }
    };
    let mut out = Vec::new();
    for (said, v, label) in visit_references(map, instruction, pose) {
        let what = label.clone().unwrap_or_else(|| "object".to_string());
        let mine: Vec<&u32> = stops.iter().filter(|id| of(id, &label)).collect();
        match v {
            Visit::Earlier if !mine.iter().any(|id| refs.contains(id)) => {
                out.push(Finding::new(
                    FindingKind::Word,
                    format!("the person said \"{said}\", a {what} visited earlier, but the plan goes to no {what} visited earlier (visited: {}): pick it with visited: 1 for the first visited, visited: -1 for the latest, or get_instance(id)", visited_of(&label)),
                    format!("which {what} do you mean? I have been to: {}", visited_of(&label)),
                ));
            }
            Visit::NotYet if !mine.is_empty() && mine.iter().all(|id| refs.contains(id)) => {
                out.push(Finding::new(
                    FindingKind::Word,
                    format!("the person said \"{said}\", a {what} not visited yet, but the plan goes back to one visited earlier (visited: {}): leave the visited ones out with not_visited: true", visited_of(&label)),
                    format!("which {what} do you mean? I have been to: {}", visited_of(&label)),
                ));
            }
            _ => {}
        }
    }
    out
}

/// "Between the two yellow tables" written as `move_in_between` of two picks of that
/// name told apart only by their counts, where the name and its filters match other than
/// two: a guess at which two (design.md: a question that says how many match). Seen on
/// the dev chat suite's dlg-ob2 with three yellow tables, as the first and the second.
/// Where exactly two match, the two picks are those two and nothing is found.
fn check_two_guessed(
    map: &IvlMap,
    instruction: &str,
    plan: &TypedPlan,
    pose: Pose,
) -> Vec<Finding> {
    let w = words(instruction);
    let said_two: Vec<String> = w
        .iter()
        .enumerate()
        .filter(|(_, x)| matches!(x.as_str(), "two" | "both" | "2"))
        .filter_map(|(i, _)| noun_after(map, &w, i, pose).map(|(_, l)| l))
        .collect();
    let mut out = Vec::new();
    for s in &plan.steps {
        let Step::Between(Object::Pick(a), Object::Pick(b)) = s else {
            continue;
        };
        let Some(label) = label_of(map, &a.name, pose) else {
            continue;
        };
        let told_apart = a.colour != b.colour
            || a.not_colour != b.not_colour
            || a.region != b.region
            || a.near.is_some()
            || b.near.is_some()
            || a.other_than.is_some()
            || b.other_than.is_some();
        if told_apart
            || label_of(map, &b.name, pose).as_deref() != Some(label.as_str())
            || !said_two.contains(&label)
        {
            continue;
        }
        let sel = Selection::<u32> {
            name: label.clone(),
            colour: a.colour.clone(),
            not_colour: a.not_colour.clone(),
            region: a.region.clone(),
            ..Selection::default()
        };
        if let Err(QueryError::NotExactlyTwo { what, count, .. }) = map.select_pair(&sel, pose) {
            let keys = [
                a.colour.as_ref().map(|c| format!("colour: \"{c}\"")),
                a.not_colour
                    .as_ref()
                    .map(|c| format!("not_colour: \"{c}\"")),
                a.region.as_ref().map(|r| format!("region: \"{r}\"")),
            ]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>();
            let sel = if keys.is_empty() {
                String::new()
            } else {
                format!(", #{{{}}}", keys.join(", "))
            };
            let f = Finding::new(
                FindingKind::Word,
                format!("the person said \"the two {what}\", but {count} match here and the plan picks two of them by their counts: write move_between_the_two(\"{label}\"{sel}) with the filters their words give"),
                format!("\"the two {what}\" names {count} here: which two do you mean?"),
            )
            .about_label(Some(label.clone()));
            if !out.contains(&f) {
                out.push(f);
            }
        }
    }
    out
}

/// Whether `plan` moves back to where it began (`move_to_start()`) or to a position
/// (`move_to([x, y])`, which a conversation's "where we started" is): the steps of
/// `grammar::RETURN_FUNCTIONS`, which the grammar requires.
pub(crate) fn plan_returns(plan: &TypedPlan) -> bool {
    steps_return(&plan.steps)
}

/// Whether one of `steps` moves back to where the plan began (see [`plan_returns`]).
pub(crate) fn steps_return(steps: &[Step]) -> bool {
    steps
        .iter()
        .any(|s| matches!(s, Step::ToStart | Step::MoveTo(_)))
}

/// Whether `instruction` says "between" (design.md: "between the two yellow tables",
/// "between the red sofa and the black one" are stops between two objects).
pub(crate) fn between_said(instruction: &str) -> bool {
    words(instruction)
        .iter()
        .any(|w| matches!(w.as_str(), "between" | "inbetween"))
}

/// The names of `names` the person said in the plural ("between the two red stools",
/// "go between the chairs"): the plural of the whole name
/// ([`map_core::matcher::plural`]: "costume racks", "shelves") as consecutive words of
/// `instruction`. "Between the piano and the black microphone" says no name in the
/// plural: it is a stop between two objects of two names, not "the two microphones".
pub(crate) fn said_in_plural<'a>(names: &'a [String], instruction: &str) -> Vec<&'a String> {
    let w = words(instruction);
    names
        .iter()
        .filter(|n| {
            let p = words(&map_core::matcher::plural(&n.to_lowercase()));
            !p.is_empty() && w.windows(p.len()).any(|x| x == p.as_slice())
        })
        .collect()
}

/// The objects the person asks to stop between two of, as design.md's "between the two
/// yellow tables" says it: "between" and, one or two words after it, "two" or "both"
/// before a name of the map in the plural ([`said_in_plural`]; colour words may come
/// between: "halfway between the two red ball racks"), where that is the only time the
/// person names that object ([`name_mentions`]). Their labels, once each. "Between the
/// two red chairs, then the black chair" names the chair again, and "between the sofa
/// and the two chairs" has no "two" right after "between": neither is one.
/// The room the person named last, alone in its clause ([`clauses`]: "..., and wrap up
/// in the medic hut", "then the ice pad", "last the rehearsal studio"): the plan's last
/// stop. Not the room the robot is in where it is the one name said ("we're in the
/// kitchen"), nor a room in a clause that says "one" ("the sofa, the one in the
/// kitchen": a room said of an object). Held-out v17 (dev since its third run): eight of
/// 42 first answers left out such a last room (most went on with steps nobody asked for,
/// the same stop again and again) and were re-asked; wb02, wb08 and wc08 were lost.
pub(crate) fn last_room_said(map: &IvlMap, instruction: &str, pose: Pose) -> Option<String> {
    let w = words(instruction);
    let (c, said) = clauses(instruction)
        .into_iter()
        .rev()
        .map(|c| {
            let said = name_mentions(map, &c, pose);
            (c, said)
        })
        .find(|(_, said)| !said.is_empty())?;
    let [(_, room)] = said.as_slice() else {
        return None;
    };
    let alone_start =
        name_mentions(map, &w, pose).len() == 1 && start_room_named_first(map, &w, pose).is_some();
    let is_room = is_region(map, room) && !map.instances.iter().any(|i| i.label == *room);
    (is_room && !alone_start && !c.iter().any(|x| matches!(x.as_str(), "one" | "ones")))
        .then(|| room.clone())
}

/// The object named first after the one "between" of `instruction` ("between the pink
/// anchor and the orange buoy": the anchor), past an article and colour words; `None`
/// where "between" is said more than once or no map object follows it.
fn first_named_between(map: &IvlMap, instruction: &str, pose: Pose) -> Option<String> {
    let w = words(instruction);
    let is_between = |x: &String| matches!(x.as_str(), "between" | "inbetween");
    let mut at = w
        .iter()
        .enumerate()
        .filter(|(_, x)| is_between(x))
        .map(|(i, _)| i);
    let (Some(i), None) = (at.next(), at.next()) else {
        return None;
    };
    let j = match w.get(i + 1).map(String::as_str) {
        Some("the" | "a" | "an") => i + 1,
        _ => i,
    };
    noun_after(map, &w, j, pose).map(|(_, l)| l)
}

pub(crate) fn pairs_said_between(map: &IvlMap, instruction: &str, pose: Pose) -> Vec<String> {
    let w = words(instruction);
    let mentions: Vec<Option<String>> = name_mentions(map, &w, pose)
        .into_iter()
        .map(|(_, n)| object_label(map, &n, pose))
        .collect();
    let mut out: Vec<String> = Vec::new();
    for (i, x) in w.iter().enumerate() {
        if !matches!(x.as_str(), "between" | "inbetween") {
            continue;
        }
        let Some(two) = (i + 1..=i + 2)
            .find(|&j| matches!(w.get(j).map(String::as_str), Some("two" | "both" | "2")))
        else {
            continue;
        };
        let Some((_, label)) = noun_after(map, &w, two, pose) else {
            continue;
        };
        let names = crate::v2::grammar::label_names(label.clone());
        let once = mentions
            .iter()
            .filter(|l| l.as_ref() == Some(&label))
            .count()
            == 1;
        if once && !said_in_plural(&names, instruction).is_empty() && !out.contains(&label) {
            out.push(label);
        }
    }
    out
}

/// A finding for each `move_between_the_two` of a name the person did not say in the
/// plural under any of its names ([`said_in_plural`]): "between the piano and the
/// black microphone" is a stop between two objects, not "the two microphones". The
/// check of the first answer's narrowing (`v2::narrow_pairs`), for a backend that takes
/// no grammar.
fn pairs_unsaid(map: &IvlMap, instruction: &str, plan: &TypedPlan, pose: Pose) -> Vec<Finding> {
    plan.steps
        .iter()
        .filter_map(|s| match s {
            Step::BetweenTwo(t) => Some(t),
            _ => None,
        })
        .filter(|t| {
            let names = object_label(map, &t.name, pose)
                .map_or_else(|| vec![t.name.clone()], crate::v2::grammar::label_names);
            said_in_plural(&names, instruction).is_empty()
        })
        .map(|t| {
            let two = map_core::matcher::plural(&t.name);
            Finding::new(
                FindingKind::Word,
                format!("the plan stops between the two {two}, but the person did not say \"the two {two}\": for a stop between two objects the person names, write move_in_between(a, b) with a pick of each"),
                "between which two objects shall I stop?",
            )
            .about_label(object_label(map, &t.name, pose))
        })
        .collect()
}

/// Whether `plan` stops between two objects (`move_in_between`, `move_between_the_two`).
/// Held-out v3 (dev) hg11: "stop between the bench and the white shelf" planned as the
/// bench nearest the shelf passed every check.
fn plan_stops_between(plan: &TypedPlan) -> bool {
    plan.steps
        .iter()
        .any(|s| matches!(s, Step::Between(..) | Step::BetweenTwo(_)))
}

/// Words that exclude what follows them (design.md: "the X that isn't yellow", "a table
/// other than the yellow one", "not the red sofa"), typed without the apostrophe too;
/// any word ending in "n't" as well ([`excludes`]).
const EXCLUDING: &[&str] = &[
    "not",
    "no",
    // "a non-yellow skate trainer" (held-out v17, dev, wb09: planned `colour: "yellow"`,
    // and no check saw it).
    "non",
    "except",
    "excluding",
    "without",
    "than",
    "but",
    "besides",
    "apart",
    "isnt",
    "arent",
    "wasnt",
    "werent",
    "dont",
    "doesnt",
    "aint",
];

/// Whether `word` excludes what follows it ([`EXCLUDING`]).
pub(crate) fn excludes(word: &str) -> bool {
    word.ends_with("n't") || EXCLUDING.contains(&word)
}

/// Whether a word of `instruction` excludes something ([`excludes`]), which a
/// `not_colour` needs.
pub(crate) fn exclusion_said(instruction: &str) -> bool {
    words(instruction).iter().any(|w| excludes(w))
}

/// Whether a colour is one the person excludes: said ([`colour_said`], a typo counting)
/// after a word that excludes ([`excludes`]) in the same clause ([`clauses`]), or one of
/// the `known` colours where a word of `instruction` excludes something. "Then the white
/// spotlight furthest west, then the microphone that isn't black" excludes black, not
/// white: held-out v8 (dev since its third run) ht02 picked the spotlight
/// `#{not_colour: "white", ...}`.
pub(crate) fn excluded_colour_said<'a>(
    instruction: &str,
    known: &'a [String],
) -> impl Fn(&str) -> bool + 'a {
    let after: Vec<String> = clauses(instruction)
        .into_iter()
        .filter_map(|w| {
            let i = w.iter().position(|x| excludes(x))?;
            Some(w[i + 1..].join(" "))
        })
        .collect();
    let text = after.join(" , ");
    let any = exclusion_said(instruction);
    let said = colour_said(&text, &[]);
    let known = colour_said("", known);
    move |c: &str| said(c) || (any && known(c))
}

/// Whether a colour is said other than after a word that excludes ([`excludes`]) in its
/// clause ([`clauses`]): a colour said of what the person means, not only of what they
/// leave out. "Any lunch table apart from the brown one" says brown only to leave it
/// out, and formats.md's tuple for it has no colour (held-out v12, dev, mx26, was
/// listed `(lunch table, None, brown)`).
pub(crate) fn kept_colour_said(instruction: &str) -> impl Fn(&str) -> bool {
    let before: Vec<String> = clauses(instruction)
        .into_iter()
        .map(|w| {
            let end = w.iter().position(|x| excludes(x)).unwrap_or(w.len());
            w[..end].join(" ")
        })
        .collect();
    colour_said(&before.join(" , "), &[])
}

/// Whether a word of `instruction` starts with one of `stems`.
fn starts_a_word(instruction: &str, stems: &[&str]) -> bool {
    words(instruction)
        .iter()
        .any(|w| stems.iter().any(|s| w.starts_with(s)))
}

/// The targets of `plan` counted in an order that `unsaid` holds, unless the person
/// `said` such an order.
fn counted_in(said: bool, plan: &TypedPlan, unsaid: impl Fn(ObjectOrder) -> bool) -> Vec<&Target> {
    if said {
        return Vec::new();
    }
    targets(plan)
        .into_iter()
        .filter(|t| unsaid(t.order))
        .collect()
}

/// The starts of words that speak of size ([`size_said`]).
const SIZE_STEMS: &[&str] = &[
    "big", "large", "small", "little", "tiny", "tini", "huge", "size",
];

/// How many words after a size word in its plain form ("small") an object's name may
/// begin for the word to be said of it: "the small red table" (two), "the big booth
/// seat" (one).
const SIZE_WORDS: usize = 3;

/// Whether a word of `instruction` speaks of the size of an object ("the biggest", "the
/// small table", "largest", "the table of the largest size"), which an order by size
/// needs. A size word in its plain form ("big", "small", "little", "tiny", "huge") speaks
/// of an object's size only where a word of an object's name (`name_words`, as
/// [`object_name_words`] lists a map's; `None`: any word, as with no map) or "one"
/// follows it within [`SIZE_WORDS`] words: "Small favour: shoot over to the booth
/// seat ..." and "a little further" say no size. Held-out v12 (dev since its third run)
/// ma02: after "Small favour", the grammar offered orders by size, and the default model
/// wrote "claw machine number 2" as the second smallest and "a ball rack other than the
/// green one" counted largest first. A superlative no reading reads
/// ([`superlative_unread`]) counts too.
pub(crate) fn size_said(instruction: &str, name_words: Option<&[String]>) -> bool {
    if superlative_unread(instruction) {
        return true;
    }
    // Within a sentence (split at ".", ":", ";", "!", "?", not at commas: "the big,
    // black sofa"): "Robot, little list: the slalom pole right at the west end, ..."
    // says no size (held-out v17, dev, wb02: offered orders by size, the default model
    // counted every pick smallest first).
    instruction
        .split(['.', ':', ';', '!', '?'])
        .any(|s| size_said_in(&words(s), name_words))
}

/// [`size_said`] in the words `w` of one sentence.
fn size_said_in(w: &[String], name_words: Option<&[String]>) -> bool {
    w.iter().enumerate().any(|(i, x)| {
        let Some(stem) = SIZE_STEMS.iter().find(|s| x.starts_with(*s)) else {
            return false;
        };
        if x != stem || *stem == "size" {
            return true;
        }
        let Some(names) = name_words else {
            return true;
        };
        w.iter().skip(i + 1).take(SIZE_WORDS).any(|y| {
            matches!(y.as_str(), "one" | "ones")
                || names.contains(y)
                || names.contains(&map_core::matcher::singular(y))
        })
    })
}

/// Targets counted by size when no word of the instruction speaks of size ("chair number
/// 3" answered with `#{ordinal: 3, order: "largest_to_smallest"}`, seen on people.nav;
/// [`size_said`], of `name_words`). No worked example may have one.
pub(crate) fn unsaid_sizes<'a>(
    instruction: &str,
    name_words: Option<&[String]>,
    plan: &'a TypedPlan,
) -> Vec<&'a Target> {
    counted_in(
        size_said(instruction, name_words),
        plan,
        ObjectOrder::is_by_size,
    )
}

/// Whether a word of `instruction` names a side or a compass direction, which a
/// directional order needs.
pub(crate) fn direction_said(instruction: &str) -> bool {
    starts_a_word(instruction, DIRECTION_STEMS)
}

/// The directional orders `instruction` counts in, as the checks read them: a count
/// from a side ([`side_count`]: "the second seat from the west" in `west_to_east`, "the
/// second to last seat from the west" in `east_to_west`, "the last seat from the west"
/// in either, as -1 or as 1 from the other end), a directional superlative ("the
/// westernmost shelf": `west_to_east`) and "furthest" + a side ([`side_after`]: "the
/// shelf furthest east": `east_to_west`). A side of a side move ("the north side of the
/// table", "left of the sofa") counts in none. `None` where some word naming a direction
/// ([`names_a_direction`]) is read by none of these ("on your left", "north-east"):
/// then nothing narrows.
///
/// Held-out v8 (hr09) and v9 (hu09, hv09), dev since their third runs: the default
/// model wrote "the second to last X from the west" as `ordinal: 2, order:
/// "west_to_east"` (the second from the west), in the first answer and in every
/// re-ask, though a worked example writes it `ordinal: 2, order: "east_to_west"`; all
/// three ended in questions.
pub(crate) fn directions_said(instruction: &str) -> Option<Vec<ObjectOrder>> {
    let w = words(instruction);
    let mut out: Vec<ObjectOrder> = Vec::new();
    let mut read = vec![false; w.len()];
    for (i, x) in w.iter().enumerate() {
        let mut found: Vec<ObjectOrder> = Vec::new();
        if x == "from" {
            if let Some(c) = side_count(&w, i) {
                read[i + 2] = true;
                found.push(c.order);
                if c.from_the_end && c.k == 1 {
                    found.push(c.order.reversed());
                }
            }
        } else if matches!(x.as_str(), "furthest" | "farthest") {
            if let Some((j, o)) = side_after(&w, i) {
                read[j] = true;
                found.push(o);
            }
        } else if let Ok((Some(1), Some(order))) = parse_ordinal_with_order(x) {
            if let Ok(o) = ObjectOrder::parse(&order) {
                read[i] = true;
                found.push(o);
            }
        }
        for o in found {
            if !out.contains(&o) {
                out.push(o);
            }
        }
    }
    let side_move = |i: usize| {
        ObjectOrder::starting_at(&w[i]).is_some()
            && matches!(
                w.get(i + 1).map(String::as_str),
                Some("of" | "side" | "hand")
            )
    };
    let unread = (0..w.len()).any(|i| names_a_direction(&w[i]) && !read[i] && !side_move(i));
    (!unread).then_some(out)
}

/// The starts of words that name a side or a compass direction ([`direction_said`]).
const DIRECTION_STEMS: &[&str] = &["north", "south", "east", "west", "left", "right"];

/// Whether `word` names a side or a compass direction ("westernmost", "left").
fn names_a_direction(word: &str) -> bool {
    DIRECTION_STEMS.iter().any(|s| word.starts_with(s))
}

/// The clauses of `instruction`, each as its words ([`words`]): split at punctuation,
/// at an arrow ("->") and at the words that join two requests ("then", "and", "after",
/// "afterwards", "finally", and "next" but not "next to").
pub(crate) fn clauses(instruction: &str) -> Vec<Vec<String>> {
    let mut out: Vec<Vec<String>> = Vec::new();
    let pieces = instruction.split(|c: char| {
        matches!(
            c,
            ',' | '.' | ';' | ':' | '!' | '?' | '>' | '(' | ')' | '\n'
        )
    });
    for piece in pieces {
        let w: Vec<String> = words(piece)
            .into_iter()
            .filter(|x| x.chars().any(char::is_alphanumeric))
            .collect();
        let mut clause: Vec<String> = Vec::new();
        for (i, x) in w.iter().enumerate() {
            let joins = match x.as_str() {
                "then" | "and" | "after" | "afterwards" | "finally" => true,
                "next" => w.get(i + 1).map(String::as_str) != Some("to"),
                _ => false,
            };
            if joins {
                out.extend((!clause.is_empty()).then(|| std::mem::take(&mut clause)));
            } else {
                clause.push(x.clone());
            }
        }
        out.extend((!clause.is_empty()).then_some(clause));
    }
    out
}

/// Words that put an object in a place ("the till in the snack bar", "the luggage rack
/// on the car deck"), read by [`places_unlisted`].
const IN_A_PLACE: &[&str] = &["in", "on", "inside"];

/// The places `instruction` puts something in ("in the kit room") whose name's first
/// word (past colour words) no tuple of `tuples` has, each as the person's words from
/// the place word on (up to three words of the name) and that first word: with no map
/// (extraction), what a re-ask names and requires. Not a side or a direction ("on the
/// left of", "on the north side"), nor a part of something ("in the middle of the two
/// desks": "of" within two words).
/// formats.md's extraction tuples list "every object the instruction mentions", rooms
/// too; read on held-out v11 and v12 (dev), the default model left out the room of "X
/// in the Y" in 7 of 8 such cases, although worked examples list it.
#[must_use]
pub fn places_unlisted(instruction: &str, tuples: &[Tuple]) -> Vec<PlaceUnlisted> {
    let listed = listed_words(tuples);
    let firsts: Vec<String> = tuples
        .iter()
        .filter_map(|t| words(&t.object).into_iter().next())
        .collect();
    let mut out = Vec::new();
    let mut before: Vec<String> = Vec::new();
    for c in clauses(instruction) {
        for i in 0..c.len() {
            if !IN_A_PLACE.contains(&c[i].as_str())
                || c.get(i + 1).map(String::as_str) != Some("the")
            {
                continue;
            }
            let mut j = i + 2;
            while c.get(j).is_some_and(|w| is_colour_word(w)) {
                j += 1;
            }
            let Some(w) = c.get(j) else { continue };
            let part_of = c[j + 1..].iter().take(2).any(|x| x == "of");
            if names_a_direction(w)
                || part_of
                || listed.contains(w)
                || listed.contains(&map_core::matcher::singular(w))
            {
                continue;
            }
            let said_before = |f: &String| before.contains(f) || c[..i].contains(f);
            out.push(PlaceUnlisted {
                phrase: c[i..(j + 3).min(c.len())].join(" "),
                word: w.clone(),
                after: firsts.iter().filter(|f| said_before(f)).count(),
            });
        }
        before.extend(c);
    }
    out
}

/// The words of the objects of `tuples`, each as listed and in the singular: what
/// [`places_unlisted`] takes as listed.
fn listed_words(tuples: &[Tuple]) -> Vec<String> {
    let mut listed = Vec::new();
    for t in tuples {
        for w in words(&t.object) {
            listed.push(map_core::matcher::singular(&w));
            listed.push(w);
        }
    }
    listed
}

/// The directional orders the person counts in ([`directions_said`]: "the
/// farthest-east front loader", "the westernmost blue dome seat", "the third chair from
/// the west") that no tuple of `tuples` counts in, either way round: with no map
/// (extraction), what a re-ask names. Empty where every one is listed, or where some
/// direction word is read by none of the forms (then nothing is known to be missing).
/// Held-out v13 (dev since its third run) nx05 and nx06: "farthest-east" and
/// "westernmost" were listed with no count and no order, in the second run and the
/// third.
#[must_use]
pub fn orders_unlisted(instruction: &str, tuples: &[Tuple]) -> Vec<ObjectOrder> {
    let listed: Vec<ObjectOrder> = tuples
        .iter()
        .filter_map(|t| t.order.as_deref())
        .filter_map(|o| ObjectOrder::parse(o).ok())
        .collect();
    directions_said(instruction)
        .unwrap_or_default()
        .into_iter()
        .filter(|o| !listed.contains(o) && !listed.contains(&o.reversed()))
        .fold(Vec::new(), |mut out, o| {
            if !out.contains(&o.reversed()) {
                out.push(o);
            }
            out
        })
}

/// The objects of `tuples` (with no map: extraction) named in a clause that says a
/// direction, or for a clause that names none of them, the nearest that does
/// ([`said_of`], [`SaidOf::Direction`]): the tuples an order the person counted in may
/// be on. `None` where no clause says one, or no tuple is named where it is said.
/// Held-out v15 (dev after its third run) rx49: "the westernmost oil drum and then the
/// engine shed" got its order on the engine shed at the re-ask.
#[must_use]
pub fn directions_said_of(instruction: &str, tuples: &[Tuple]) -> Option<Vec<String>> {
    let names: Vec<(Vec<String>, &str)> = tuples
        .iter()
        .map(|t| (tuple_name(t), t.object.as_str()))
        .filter(|(w, _)| !w.is_empty())
        .collect();
    let name_at = |w: &[String], j: usize| {
        names
            .iter()
            .filter(|(n, _)| said_at(w, j, n))
            .max_by_key(|(n, _)| n.len())
            .map(|(n, o)| ((*o).to_string(), n.len()))
    };
    said_of(instruction, SaidOf::Direction, name_at).filter(|o| !o.is_empty())
}

/// The words of `t`'s object, each in the singular: how [`said_at`] matches it.
fn tuple_name(t: &Tuple) -> Vec<String> {
    words(&t.object)
        .iter()
        .map(|w| map_core::matcher::singular(w))
        .collect()
}

/// Whether the words `name` (in the singular) are said at word `i` of `w`, each word of
/// `w` read in the singular.
fn said_at(w: &[String], i: usize, name: &[String]) -> bool {
    i + name.len() <= w.len()
        && w[i..i + name.len()]
            .iter()
            .map(|x| map_core::matcher::singular(x))
            .eq(name.iter().cloned())
}

/// A place the objects line lists no word of ([`places_unlisted`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlaceUnlisted {
    /// The person's words from the place word on ("in the kit room").
    pub phrase: String,
    /// The first word of the place's name ("kit").
    pub word: String,
    /// How many of the tuples name an object (by its first word) said before the place:
    /// where, in the order of mention, the place's tuple goes.
    pub after: usize,
}

/// Articles and the other words that begin a phrase naming an object ("the", "each",
/// "another"), for [`names_cut`].
const DETERMINERS: &[&str] = &[
    "the",
    "a",
    "an",
    "this",
    "that",
    "these",
    "those",
    "my",
    "your",
    "our",
    "their",
    "its",
    "his",
    "her",
    "each",
    "every",
    "any",
    "some",
    "all",
    "both",
    "either",
    "neither",
    "no",
    "another",
    "other",
    "same",
    "which",
    "whichever",
    "what",
    "few",
    "several",
    "many",
];

/// Words that are no part of an object's name, for [`names_cut`] (with
/// [`DETERMINERS`]): pronouns, prepositions, the words that join or end a request, and the
/// words of courtesy. (Counts, colours, sizes, directions and superlatives are read by
/// their own rules.)
const FUNCTION_WORDS: &[&str] = &[
    "to",
    "from",
    "of",
    "in",
    "on",
    "at",
    "by",
    "near",
    "next",
    "beside",
    "behind",
    "between",
    "with",
    "without",
    "into",
    "onto",
    "over",
    "under",
    "past",
    "toward",
    "towards",
    "around",
    "across",
    "along",
    "for",
    "up",
    "down",
    "off",
    "out",
    "through",
    "via",
    "than",
    "apart",
    "except",
    "besides",
    "opposite",
    "against",
    "inside",
    "outside",
    "beyond",
    "after",
    "before",
    "close",
    "round",
    "about",
    "alongside",
    "beneath",
    "below",
    "above",
    "facing",
    "and",
    "then",
    "or",
    "but",
    "nor",
    "so",
    "while",
    "once",
    "if",
    "when",
    "where",
    "until",
    "plus",
    "also",
    "too",
    "again",
    "please",
    "pls",
    "thanks",
    "thank",
    "cheers",
    "ta",
    "now",
    "just",
    "only",
    "there",
    "here",
    "is",
    "are",
    "be",
    "was",
    "it",
    "one",
    "ones",
    "you",
    "me",
    "us",
    "i",
    "we",
    "them",
    "him",
    "it's",
    "that's",
    "thats",
    "who",
    "whose",
    "counting",
    "counted",
    "number",
];

/// Words after which a name's next word reads as its end: how an object is counted or
/// placed ("the ball return counting from the west", "the ball return by the bench").
const AFTER_A_NAME: &[&str] = &[
    "counting", "counted", "from", "by", "near", "nearest", "closest", "furthest", "farthest",
    "next", "in", "on", "at", "beside", "behind", "to", "of", "that", "which", "with",
];

/// Whether `w` is a count, a colour, a size, a direction or a superlative ("third",
/// "red", "big", "west", "northernmost", "biggest"): a word that says which object, never
/// what it is.
fn says_which(w: &str) -> bool {
    said_count(w).is_some()
        || matches!(w, "last" | "final" | "middle" | "next" | "penultimate")
        || is_colour_word(w)
        || w.chars().next().is_some_and(|c| c.is_ascii_digit())
        || SIZE_STEMS.iter().any(|s| w.starts_with(s))
        || names_a_direction(w)
        || w.ends_with("est")
        || w.ends_with("most")
}

/// Whether `w` may be a word of an object's name: none of [`FUNCTION_WORDS`], nor a word
/// that [`says_which`] object.
fn may_name(w: &str) -> bool {
    !FUNCTION_WORDS.contains(&w) && !DETERMINERS.contains(&w) && !says_which(w)
}

/// The objects of `tuples` (with no map: extraction) that the person named with a word
/// more, right next to the words listed: a word before them that follows an article, a
/// count, a colour or another word that [`says_which`] ("the third *waiting* bench",
/// "the *oak* barrel"), or a word after them that is followed by a word of
/// [`AFTER_A_NAME`] ("the ball *return* counting from the west"); neither word is any
/// of [`FUNCTION_WORDS`], says which object, or is said as a word of some tuple's object
/// (where all that object's words are said together). For one-word objects (stop 77:
/// one- and two-word); a spaced dash ends a phrase as punctuation does.
///
/// Two-word objects are taken whole since stop 78: on held-out v15's extraction cases
/// (dev after its third run) the only two found so were right answers, "the tank dolly
/// sitting closest to ..." (`tank dolly sitting`) and "the one-from-the-end viewing
/// seat" (`end viewing seat`), and every name found cut on the dev sets before was
/// listed by one word.
///
/// Until stop 78 a word of any tuple's object was never taken as left out, wherever it
/// was said: held-out v13 (dev) nx34, "the wax bench closest to the red wax heater",
/// listed `(bench, None, red), (wax heater, None, red)`, and the "wax" of "wax bench" was
/// taken as the heater's.
///
/// formats.md's tuple holds "the instruction's own word" for the object; read on
/// held-out v11 and v12's extraction cases (dev), 11 of 20 misses listed a name less one
/// of its words ("waiting bench" as `bench`, "ball return" as `ball`), although worked
/// examples list such names whole. Of the 565 cases of the extraction suites written
/// before held-out v13 (each `expected` answer read as if the model had written it), none
/// is found.
#[must_use]
pub fn names_cut(instruction: &str, tuples: &[Tuple]) -> Vec<NameCut> {
    let single = |w: &str| map_core::matcher::singular(w);
    let phrases: Vec<Vec<String>> = instruction
        .split(" - ")
        .flat_map(|p| p.split(" \u{2013} "))
        .flat_map(clauses)
        .collect();
    let names: Vec<Vec<String>> = tuples.iter().map(tuple_name).collect();
    // Where each name is said: the words some tuple's object is listed by, at each place
    // they are said together. A word there is that object's, not one left out of another.
    let covered: Vec<Vec<bool>> = phrases
        .iter()
        .map(|c| {
            let mut cov = vec![false; c.len()];
            for name in names.iter().filter(|n| !n.is_empty()) {
                for i in (0..c.len()).filter(|&i| said_at(c, i, name)) {
                    cov[i..i + name.len()].iter_mut().for_each(|x| *x = true);
                }
            }
            cov
        })
        .collect();
    let mut out = Vec::new();
    for (index, (t, name)) in tuples.iter().zip(&names).enumerate() {
        let n = name.len();
        if n != 1 {
            continue;
        }
        let found = phrases.iter().zip(&covered).find_map(|(c, cov)| {
            (0..c.len())
                .find(|&i| said_at(c, i, name))
                .map(|i| (c, cov, i))
        });
        let Some((c, cov, i)) = found else { continue };
        let free = |j: usize| may_name(&c[j]) && !cov[j];
        let opens = |w: &str| DETERMINERS.contains(&w) || says_which(w);
        let before = (i >= 2 && free(i - 1) && opens(&c[i - 2]))
            .then(|| format!("{} {}", c[i - 1], name.join(" ")));
        let after = c
            .get(i + n + 1)
            .filter(|next| free(i + n) && AFTER_A_NAME.contains(&next.as_str()))
            .map(|_| format!("{} {}", name.join(" "), single(&c[i + n])));
        if let Some(said) = before.or(after) {
            out.push(NameCut {
                said,
                listed: t.object.clone(),
                index,
            });
        }
    }
    out
}

/// An object the objects line lists with fewer words than the person named it with
/// ([`names_cut`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NameCut {
    /// The name with the word more, in the objects line's form ("oak barrel").
    pub said: String,
    /// The object as listed ("barrel").
    pub listed: String,
    /// Which tuple of the line it is (from 0).
    pub index: usize,
}

/// What a clause may say of the objects it names, and only of those.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SaidOf {
    /// A side or a compass direction ("the 2nd freezer counting from the west"): a
    /// directional order. Held-out v8 (dev since its third run) hr04: "the penultimate
    /// microscope first. Next the 2nd freezer counting from the west" counted the
    /// microscope west to east too; ht04 counted "the penultimate spotlight" from the
    /// east said of the next mirror.
    Direction,
    /// A count of two or more ([`said_count`]: "2nd", "third", "penultimate"): an
    /// ordinal of two or more from either end ("the first", "the last" are said in too
    /// many ways to place). Held-out v8 (dev) ht12: "piano, purple costume rack, 2nd
    /// stool from the west" wrote the stool's 2 on the costume rack too.
    Count,
    /// The far end ([`speaks_of_the_far_end`]: "furthest", "farthest", "second to
    /// last"): the order `far_to_near`. Held-out v9 (dev since its third run) hv04:
    /// "the second-to-last luggage trolley" counted the green table of the next clause
    /// `far_to_near` too.
    FarEnd,
}

impl SaidOf {
    /// Whether the words `w` (of a clause) say it. A count may take more than one word
    /// ([`counts_in`]: "the last but one").
    fn in_words(self, w: &[String]) -> bool {
        match self {
            SaidOf::Direction => w.iter().any(|x| names_a_direction(x)),
            SaidOf::Count => counts_in(w).iter().any(|(k, _)| k.abs() >= 2),
            SaidOf::FarEnd => w.iter().any(|x| speaks_of_the_far_end(x)),
        }
    }

    /// Whether target `t` selects with it.
    fn in_target(self, t: &Target) -> bool {
        match self {
            SaidOf::Direction => t.order.is_directional(),
            SaidOf::Count => t.ordinal.abs() >= 2,
            // Counted from the far end of the default order too: -1 is the farthest.
            SaidOf::FarEnd => {
                t.order == ObjectOrder::FarToNear
                    || (t.order == ObjectOrder::NearToFar && t.ordinal < 0)
            }
        }
    }
}

/// The objects `what` is said of: the labels (`name_at`: the label a name beginning at
/// a word has, and its length in words) named in a clause ([`clauses`]) that says it,
/// and for such a clause that names no object ("the chairs, the one furthest west",
/// "counting from the east, the second mirror") those of the nearest clauses before
/// and after it that name one (for a count, the nearest before it:
/// [`nearest_named_before`]). `None` when no clause says it, or a clause that does names
/// no object and no other clause names one.
pub(crate) fn said_of(
    instruction: &str,
    what: SaidOf,
    name_at: impl Fn(&[String], usize) -> Option<(String, usize)>,
) -> Option<Vec<String>> {
    let parts = clauses(instruction);
    let named: Vec<Vec<String>> = parts.iter().map(|w| named_in(w, &name_at)).collect();
    let mut out: Vec<String> = Vec::new();
    let mut any = false;
    for (i, w) in parts.iter().enumerate() {
        if !what.in_words(w) {
            continue;
        }
        any = true;
        if !named[i].is_empty() {
            out.extend(named[i].iter().cloned());
            continue;
        }
        let near = if what == SaidOf::Count {
            nearest_named_before(&named, i)
        } else {
            nearest_named(&named, i)
        };
        if near.is_empty() {
            return None;
        }
        out.extend(near.into_iter().cloned());
    }
    out.sort();
    out.dedup();
    any.then_some(out)
}

/// The labels of the nearest clauses before and after clause `i` that name one (`named`:
/// each clause's labels, [`named_in`]): whose [`said_of`] and [`regions_said_of`] take
/// what a clause naming no object says. Empty where no other clause names one.
fn nearest_named(named: &[Vec<String>], i: usize) -> Vec<&String> {
    let before = named[..i].iter().rev().find(|l| !l.is_empty());
    let after = named
        .get(i + 1..)
        .into_iter()
        .flatten()
        .find(|l| !l.is_empty());
    before.into_iter().chain(after).flatten().collect()
}

/// The labels of the nearest clause before clause `i` that names one, else of the
/// nearest after it: whose a count said in a clause naming no object is. A count trails
/// the name it counts where a full stop cuts it off ("ski rack nr. 2"; "chair number,
/// 3"). Held-out v13 (dev since its third run) na02: "next ski rack nr. 2, then a wing
/// chair that isn't green" placed the 2 on both, and the plan's `#{ordinal: 2}` for the
/// wing chair passed, a wrong stop in every run.
fn nearest_named_before(named: &[Vec<String>], i: usize) -> Vec<&String> {
    match named[..i].iter().rev().find(|l| !l.is_empty()) {
        Some(before) => before.iter().collect(),
        None => nearest_named(named, i),
    }
}

/// The labels named in the words `w` of a clause, in order (`name_at`: the label a name
/// beginning at a word has, and its length in words), each name read once.
fn named_in(
    w: &[String],
    name_at: &impl Fn(&[String], usize) -> Option<(String, usize)>,
) -> Vec<String> {
    let mut labels = Vec::new();
    let mut j = 0;
    while j < w.len() {
        match name_at(w, j) {
            Some((label, len)) => {
                labels.push(label);
                j += len.max(1);
            }
            None => j += 1,
        }
    }
    labels
}

/// [`said_of`] on `map`: a name is one the map holds (not a region), else a typo of one
/// (not a colour word).
pub(crate) fn said_of_map(
    map: &IvlMap,
    instruction: &str,
    pose: Pose,
    what: SaidOf,
) -> Option<Vec<String>> {
    said_of(instruction, what, |w, j| map_name_at(map, w, j, pose))
}

/// The label of the map's object named at `w[j]` and the name's length in words, as
/// [`said_of_map`] reads names: one the map holds (not a region), else a typo of one
/// (not a colour word).
fn map_name_at(map: &IvlMap, w: &[String], j: usize, pose: Pose) -> Option<(String, usize)> {
    if let Some((_, label, len)) = label_at(map, w, j, pose) {
        return Some((label, len));
    }
    if is_colour_word(&w[j]) {
        return None;
    }
    typed_label_at(map, w, j).map(|(_, label)| (label, 1))
}

/// Per label the person named ([`map_name_at`]), in order of first mention, the regions
/// said of it: those named ([`region_said`]) in a clause ([`clauses`]) that names it,
/// and for a clause that names a region and no object ("in the kitchen, the second
/// chair", "then into triage") those of the nearest clauses before and after it that
/// name one, as [`said_of`] places a direction. A label with no region said of it is
/// listed with none.
///
/// Held-out v10 (dev since its third run, read per task at stop 72) ka05: "Then find the
/// wheelchair closest to the blue hospital bed. Then the westernmost stretcher, and then
/// into triage." picked the wheelchair `#{region: "triage", near: ...}`, a wrong stop.
pub(crate) fn regions_said_of(
    map: &IvlMap,
    instruction: &str,
    pose: Pose,
) -> Vec<(String, Vec<String>)> {
    let exact = object_name_words(map);
    let parts = clauses(instruction);
    let name_at = |w: &[String], j: usize| map_name_at(map, w, j, pose);
    let named: Vec<Vec<String>> = parts.iter().map(|w| named_in(w, &name_at)).collect();
    let rooms: Vec<Vec<String>> = parts
        .iter()
        .map(|w| {
            let said = region_said(&w.join(" "), &exact);
            map.regions
                .iter()
                .filter(|r| said(&r.name))
                .map(|r| r.name.clone())
                .collect()
        })
        .collect();
    let mut out: Vec<(String, Vec<String>)> = Vec::new();
    let mut add = |label: &str, regions: &[String]| {
        let i = match out.iter().position(|(l, _)| l == label) {
            Some(i) => i,
            None => {
                out.push((label.to_string(), Vec::new()));
                out.len() - 1
            }
        };
        for r in regions {
            if !out[i].1.contains(r) {
                out[i].1.push(r.clone());
            }
        }
    };
    for (i, labels) in named.iter().enumerate() {
        for l in labels {
            add(l, &rooms[i]);
        }
    }
    for (i, regions) in rooms.iter().enumerate() {
        if regions.is_empty() || !named[i].is_empty() {
            continue;
        }
        for l in nearest_named(&named, i) {
            add(l, regions);
        }
    }
    out
}

/// A finding for each target selected in a region said in the instruction but not of
/// its object ([`regions_of_others`]): the check of
/// [`Vocabulary::regions_of`](super::grammar::Vocabulary::regions_of)'s narrowing
/// (`v2::narrow_regions_of_said`) for backends that take no grammar. Outside a
/// conversation only; the caller asks it where `PlanOptions::regions_of_said` is on.
pub(crate) fn check_regions_of_others(
    map: &IvlMap,
    instruction: &str,
    plan: &TypedPlan,
    pose: Pose,
) -> Vec<Finding> {
    unsaid_findings(
        map,
        pose,
        plan,
        regions_of_others(map, instruction, pose, plan),
        |t| {
            let region = t.region.as_deref().unwrap_or_default();
            format!("the plan picks the {} in the {region}, but the person did not put the {} in the {region}: leave the {}'s region out unless their words about it name a room", t.name, t.name, t.name)
        },
        |t| format!("which {} do you mean", t.name),
    )
}

/// Targets selected in a region ([`Target::region`]) said in the instruction but not of
/// their object ([`regions_said_of`]). A region said nowhere is [`unsaid_regions`]'.
pub(crate) fn regions_of_others<'a>(
    map: &IvlMap,
    instruction: &str,
    pose: Pose,
    plan: &'a TypedPlan,
) -> Vec<&'a Target> {
    let said = region_said(instruction, &object_name_words(map));
    let of = regions_said_of(map, instruction, pose);
    targets(plan)
        .into_iter()
        .filter(|t| {
            t.region.as_deref().is_some_and(|r| {
                said(r)
                    && !object_label(map, &t.name, pose).is_some_and(|l| {
                        of.iter()
                            .any(|(x, rs)| *x == l && rs.iter().any(|x| x == r))
                    })
            })
        })
        .collect()
}

/// Words that point back at an object named in an earlier clause ("then the lamp next to
/// it"): [`anchors_said`].
const POINTING_BACK: &[&str] = &["it", "its", "them", "that", "this"];

/// Per label the person named ([`map_name_at`]), the labels it may be picked near
/// (`near:`): those named in a clause ([`clauses`]) that names it, other than itself
/// unless it is named twice there ("the teller desk closest to the black chair": the
/// chair for the teller desk and the teller desk for the chair), and, in a clause with
/// a word pointing back ([`POINTING_BACK`]: "then the lamp next to it"), those named in
/// the clauses before. A label named in no clause is not listed: it has none.
///
/// Held-out v9 (dev since its third run, read per task at stop 67): in hu14 and hv14
/// the default model wrote "whichever sofa is nearest to you, then pull up to the right
/// of the blue teller desk" as the sofa near the teller desk (a wrong stop no check
/// saw), in hu05 "the teller desk closest to the black chair. Westernmost sofa after
/// that" as the teller desk near the black sofa, and in hw10 "the watering can closest
/// to the grey planter" as the watering can near a plant.
pub(crate) fn anchors_said(
    map: &IvlMap,
    instruction: &str,
    pose: Pose,
) -> Vec<(String, Vec<String>)> {
    anchors_said_by(instruction, |w, j| map_name_at(map, w, j, pose))
}

/// [`anchors_said`] with names read by `name_at` (the label a name beginning at a word
/// has, and its length in words), as [`said_of`] reads them.
pub(crate) fn anchors_said_by(
    instruction: &str,
    name_at: impl Fn(&[String], usize) -> Option<(String, usize)>,
) -> Vec<(String, Vec<String>)> {
    let mut out: Vec<(String, Vec<String>)> = Vec::new();
    let mut before: Vec<String> = Vec::new();
    for w in clauses(instruction) {
        let named = named_in(&w, &name_at);
        let back = w.iter().any(|x| POINTING_BACK.contains(&x.as_str()));
        for (i, label) in named.iter().enumerate() {
            let mut anchors: Vec<String> = named
                .iter()
                .enumerate()
                .filter(|(k, _)| *k != i)
                .map(|(_, l)| l.clone())
                .collect();
            if back {
                anchors.extend(before.iter().cloned());
            }
            match out.iter_mut().find(|(l, _)| l == label) {
                Some((_, list)) => list.extend(anchors),
                None => out.push((label.clone(), anchors)),
            }
        }
        before.extend(named);
    }
    for (_, list) in &mut out {
        list.sort();
        list.dedup();
    }
    out
}

/// Targets that select with `what` whose object (`label` reads a target's name) the
/// person named in no clause that says it (`said`, from [`said_of`]): the grammar
/// offers it only to those (`v2::narrow_to_words`).
pub(crate) fn said_of_others<'a>(
    said: Option<&[String]>,
    what: SaidOf,
    plan: &'a TypedPlan,
    label: impl Fn(&str) -> Option<String>,
) -> Vec<&'a Target> {
    let Some(said) = said else {
        return Vec::new();
    };
    targets(plan)
        .into_iter()
        .filter(|t| what.in_target(t) && label(&t.name).is_some_and(|l| !said.contains(&l)))
        .collect()
}

/// Whether a word of `instruction` speaks of the far end ("the farthest", "furthest
/// from you", "far away", "the most distant") or of the end of the default order ("the
/// second to last", "the penultimate": design.md counts them in `far_to_near`), which the
/// order `far_to_near` needs.
pub(crate) fn far_end_said(instruction: &str) -> bool {
    starts_a_word(instruction, FAR_END_STEMS) || superlative_unread(instruction)
}

/// Whether `instruction` says a superlative that no reading of the grammar's narrowing
/// reads: a word of six letters or more ending in "est", or "most" or "least" (not
/// after "at") with the word after it (or none), where that word is not a direction, a
/// size, the far end ([`FAR_END_STEMS`]) or the near end ("nearest", "closest": the
/// default order). Where one is said the grammar does not narrow the orders by size or
/// the far end ([`size_said`], [`far_end_said`]): what such a word means is the model's
/// to read, and narrowing on the words read would leave it no way to write it. Read on
/// held-out v14 and v15 (dev): "the remotest vinyl crate", "the parcel locker that's the
/// longest way from you", "the most compact picnic table", "the fattest picnic table",
/// "the one with the least" were each offered no far end or no size, and none was
/// listed or planned right.
pub(crate) fn superlative_unread(instruction: &str) -> bool {
    let w = words(instruction);
    let read = |x: &str| {
        names_a_direction(x)
            || SIZE_STEMS.iter().any(|s| x.starts_with(s))
            || speaks_of_the_far_end(x)
            || matches!(x, "nearest" | "closest")
    };
    w.iter().enumerate().any(|(i, x)| {
        if matches!(x.as_str(), "most" | "least") {
            i.checked_sub(1).and_then(|j| w.get(j)).map(String::as_str) != Some("at")
                && w.get(i + 1).is_none_or(|y| !read(y))
        } else {
            x.chars().count() >= 6 && x.ends_with("est") && !read(x)
        }
    })
}

/// The starts of words that speak of the far end ([`far_end_said`]). Not "end": held-out
/// v10 (dev) kb02, "... and end on the platform", then offered the turnstile "furthest
/// west" a count from the end, and the default model wrote it `ordinal: -1`.
const FAR_END_STEMS: &[&str] = &["far", "furth", "distan", "last", "penult"];

/// Whether `word` starts as a word that speaks of the far end does ("most distant",
/// "far away", "lastly"): the one reading [`far_end_said`] and [`ends_said_of_sides`]
/// share, so that no count from the end the first sees is missed by the second.
fn speaks_of_the_far_end(word: &str) -> bool {
    FAR_END_STEMS.iter().any(|s| word.starts_with(s))
}

/// Targets counted in `far_to_near` when no word of the instruction speaks of the far
/// end ("third stool please" answered with `#{ordinal: 3, order: "far_to_near"}`, the
/// third farthest, seen on held-out v2's hd07 and scored wrong by no check). No worked
/// example may have one.
pub(crate) fn unsaid_far_ends<'a>(instruction: &str, plan: &'a TypedPlan) -> Vec<&'a Target> {
    counted_in(far_end_said(instruction), plan, |o| {
        o == ObjectOrder::FarToNear
    })
}

/// The counts `instruction` says ([`counts_in`], [`said_count`]: 3 for "third", "3rd",
/// "thrid"; -2 for "penultimate"; 2 for "next to last").
pub(crate) fn counts_said(instruction: &str) -> Vec<i64> {
    // A count from the end in more than one word ("next to last", "last but one") says
    // its count from either end, as "second to last" always has ("second": 2).
    counts_in(&words(instruction))
        .into_iter()
        .map(|(k, r)| if r.len() > 1 { k.abs() } else { k })
        .collect()
}

/// The counts a selection may take for `instruction`: those it says ([`counts_said`]),
/// and 2 (either end) where the person counts from a side or speaks of the far end
/// ([`direction_said`], [`far_end_said`]). The second from an end is said in many ways
/// that name no number ("the one before the end when you count from the west", "one shy
/// of the end", "next-to-farthest"), as the first and the last are; where no side and no
/// far end is said, a 2 stays unsaid ("the small table next to the blue bed" written
/// `#{ordinal: 2, ...}`, people.nav). Held-out v15 (dev since its third run): ra09, rb09
/// and rc09 (the second from the east, said as one before the end counted from the west)
/// could not be written, and all three went to another wheel set, coral tank or press.
pub(crate) fn counts_offered(instruction: &str) -> Vec<i64> {
    let mut counts = counts_said(instruction);
    if direction_said(instruction) || far_end_said(instruction) {
        counts.push(2);
    }
    counts
}

/// Whether an ordinal is said by the counts of [`counts_said`]: 1 and -1 always (the
/// first and the last are said in too many ways), k and -k when k is said, -2 when
/// "penultimate" is.
pub(crate) fn ordinal_said(said: &[i64], ordinal: i64) -> bool {
    ordinal.abs() <= 1
        || said
            .iter()
            .any(|&k| k == ordinal.abs() || (k == -2 && ordinal == -2))
}

/// The unsaid colours ([`unsaid_colours`]) that change what the plan picks ("go to the
/// sofa" answered with `get_obj("sofa", #{colour: "black"})` on a map of a red and a
/// black sofa). Measured on people.nav, the default model adds the map's colour to most
/// objects it names (the silver fridge of a map with one fridge): such a colour excludes
/// no instance of the object and is not a finding; nor are two different colours that
/// tell apart the two objects of one `move_in_between` of the same name ("between the two
/// sofas" as the black sofa and the red one). A made-up colour that does exclude one is
/// re-asked, never dropped here.
fn check_unsaid_colours(
    map: &IvlMap,
    instruction: &str,
    known: &[String],
    plan: &TypedPlan,
    pose: Pose,
) -> Vec<Finding> {
    // The targets of `move_in_between(a, b)` on one name with different colours.
    let mut pairs: Vec<&Target> = Vec::new();
    for s in &plan.steps {
        if let Step::Between(Object::Pick(a), Object::Pick(b)) = s {
            let same = label_of(map, &a.name, pose)
                .is_some_and(|l| label_of(map, &b.name, pose) == Some(l));
            if same
                && a.colour.is_some()
                && b.colour.is_some()
                && !same_colour(a.colour.as_deref(), b.colour.as_deref().unwrap_or_default())
            {
                pairs.extend([a, b]);
            }
        }
    }
    let mut out: Vec<Finding> = Vec::new();
    for (t, field, c) in unsaid_colours(instruction, known, plan) {
        if pairs.iter().any(|p| std::ptr::eq(*p, t)) {
            continue;
        }
        let label = label_of(map, &t.name, pose);
        let of_label: Vec<_> = map
            .instances
            .iter()
            .filter(|i| label.as_deref() == Some(i.label.as_str()))
            .collect();
        let excludes = match field {
            "colour" => of_label
                .iter()
                .any(|i| !same_colour(i.colour.as_deref(), c)),
            _ => of_label.iter().any(|i| same_colour(i.colour.as_deref(), c)),
        };
        if !excludes {
            continue;
        }
        let mut f = Finding::new(
            FindingKind::Word,
            format!(
                "the plan picks a {} with {field} \"{c}\", but the person did not say \"{c}\": give a colour only where the person's words do",
                t.name
            ),
            match field {
                "colour" => format!("do you mean a {c} {}?", t.name),
                _ => format!("do you mean a {} that is not {c}?", t.name),
            },
        );
        if let Some(label) = label {
            f = f.barring(Bar::UnsaidColours { label });
        }
        push_first(&mut out, f.at_target(plan, t));
    }
    out
}

/// Picks that select on a colour the person said only of other objects: every time
/// they said it, it was right before another object's name ([`colour_mentions`]: "the
/// planter closest to the grey fountain, then the westernmost potting bench" says grey
/// of the fountain, never of the potting bench). A colour said after a name ("the chair
/// that's red", but not "the sofa, the red one": [`colour_noun`]) is of no name, and such a colour is not judged
/// here. Held-out v9 (dev) hw05: that plan picked the potting bench with
/// `colour: "grey"`, a wrong stop that no check saw (the colour was said, so the unsaid
/// colours' check let it pass). The re-ask's bar ([`Bar::UnsaidColours`]) leaves out of
/// that object's picks the colours said only of others. Outside a conversation, where
/// an earlier instruction may have said the colour of it.
fn check_colours_of_others(
    map: &IvlMap,
    instruction: &str,
    plan: &TypedPlan,
    pose: Pose,
) -> Vec<Finding> {
    let said_only_of = colour_said_only_of(map, instruction, pose);
    let mut out: Vec<Finding> = Vec::new();
    for t in targets(plan) {
        let Some(label) = object_label(map, &t.name, pose) else {
            continue;
        };
        for (field, c) in [("colour", &t.colour), ("not_colour", &t.not_colour)] {
            let Some(c) = c.as_deref() else { continue };
            let Some(mut of) = said_only_of(c) else {
                continue;
            };
            if of.contains(&label) {
                continue;
            }
            of.dedup();
            let others = of.join(" and the ");
            let f = Finding::new(
                FindingKind::Word,
                format!("the plan picks the {} with {field} \"{c}\", but the person said \"{c}\" of the {others}, not of the {label}: give the {label} a colour only where their words say one of it", t.name),
                format!(
                    "which {} do you mean (you said {c} of the {others})? there are {}",
                    t.name,
                    describe_label(map, &label)
                ),
            )
            .barring(Bar::UnsaidColours { label })
            .at_target(plan, t);
            push_first(&mut out, f);
            break;
        }
    }
    out
}

/// Targets counted in a direction ("west_to_east", "left_to_right") when no word of the
/// instruction names a side or a compass direction ("the third chair" answered with
/// `#{ordinal: 3, order: "north_to_south"}`, seen on people.nav). No worked example may
/// have one.
pub(crate) fn unsaid_directions<'a>(instruction: &str, plan: &'a TypedPlan) -> Vec<&'a Target> {
    counted_in(
        direction_said(instruction),
        plan,
        ObjectOrder::is_directional,
    )
}

/// Targets counted with an ordinal of 2 or more (either end: -2 is the second to last)
/// when no word of the instruction says that count ("the small table next to the blue
/// bed" answered with `#{ordinal: 2, near: ...}`, seen on people.nav; "the yellow table
/// that's furthest from you" with `#{ordinal: 3, order: "far_to_near"}`). The first and
/// the last (1, -1) are said in too many ways ("nearest", "furthest", "the last") to be
/// judged here; [`check_words`] checks the superlatives. In a conversation too: "the
/// other one" leaves a visited instance out (`other_than`) and "the same one" names it
/// (`get_instance`); measured on the chat suite (dev), with counts open there the default
/// model wrote a visited instance's id as the ordinal ("now the other red chair" after
/// red chair 9 as `#{ordinal: 9, colour: "red"}`). No worked example may have one.
pub(crate) fn unsaid_ordinals<'a>(instruction: &str, plan: &'a TypedPlan) -> Vec<&'a Target> {
    let said = counts_offered(instruction);
    targets(plan)
        .into_iter()
        .filter(|t| !ordinal_said(&said, t.ordinal))
        .collect()
}

/// Targets that exclude a colour (`not_colour`) the person does not exclude
/// ([`excluded_colour_said`]: said after a word that excludes, in its clause): the grammar
/// offers `not_colour` only with those (`v2::narrow_exclusions`). A colour the person never said is [`unsaid_colours`]'
/// finding, not this one; `known` as there. In a conversation (`in_chat`) not judged.
/// No worked example may have one.
pub(crate) fn unsaid_exclusions<'a>(
    instruction: &str,
    known: &[String],
    in_chat: bool,
    plan: &'a TypedPlan,
) -> Vec<&'a Target> {
    if in_chat {
        return Vec::new();
    }
    let said = colour_said(instruction, known);
    let excluded = excluded_colour_said(instruction, known);
    targets(plan)
        .into_iter()
        .filter(|t| {
            t.not_colour
                .as_deref()
                .is_some_and(|c| said(c) && !excluded(c))
        })
        .collect()
}

/// The targets that count from the end of `far_to_near` or of an order by size
/// (a negative ordinal there): what a positive ordinal in the default order, or in the
/// other size order, says the way it is said. The grammar offers only that way
/// ([`super::grammar`]); the default model wrote the other for the opposite ("the bed
/// that's farthest away" as `#{ordinal: -1, order: "far_to_near"}`, the nearest).
pub(crate) fn counted_from_the_end(plan: &TypedPlan) -> Vec<&Target> {
    targets(plan)
        .into_iter()
        .filter(|t| t.ordinal < 0 && !end_reads_as_said(t.order))
        .collect()
}

/// Whether a count from the end of `order` reads as it is said: not in `far_to_near`
/// and not in an order by size (see [`counted_from_the_end`]). The grammar offers a
/// negative ordinal only in these orders.
pub(crate) fn end_reads_as_said(order: ObjectOrder) -> bool {
    order != ObjectOrder::FarToNear && !order.is_by_size()
}

/// What a finding tells the model about a target.
type Note<'a> = dyn Fn(&Target) -> String + 'a;

/// Findings for targets that select on something the person did not say, one per
/// distinct message: `to_model` says what to leave out, the question names the object's
/// candidates where `map` holds it.
fn unsaid_findings(
    map: &IvlMap,
    pose: Pose,
    plan: &TypedPlan,
    targets: Vec<&Target>,
    to_model: impl Fn(&Target) -> String,
    to_user: impl Fn(&Target) -> String,
) -> Vec<Finding> {
    let mut out: Vec<Finding> = Vec::new();
    for t in targets {
        let label = label_of(map, &t.name, pose);
        let question = match &label {
            Some(l) => format!("{}? there are {}", to_user(t), describe_label(map, l)),
            None => format!("{}?", to_user(t)),
        };
        let f = Finding::new(FindingKind::Word, to_model(t), question)
            .about_label(label)
            .at_target(plan, t);
        push_first(&mut out, f);
    }
    out
}

/// Adds `f` unless a finding with its note to the model is there already: the first,
/// the one at the earliest step of the plan, stands.
fn push_first(out: &mut Vec<Finding>, f: Finding) {
    if !out.iter().any(|x| x.to_model == f.to_model) {
        out.push(f);
    }
}

/// The index of the step of `plan` that holds the target `t` (a reference into it).
fn step_of(plan: &TypedPlan, t: &Target) -> Option<usize> {
    plan.steps
        .iter()
        .position(|s| s.targets().into_iter().any(|x| std::ptr::eq(x, t)))
}

/// Where the instruction names each map object (not a region): the word index of each
/// name (a label or a synonym, two words before one: "coffee table"), in order.
fn object_mentions(map: &IvlMap, w: &[String], pose: Pose) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut k = 0;
    while k < w.len() {
        match label_at(map, w, k, pose) {
            Some((_, label, len)) => {
                out.push((k, label));
                k += len;
            }
            None => k += 1,
        }
    }
    out
}

/// The labels `plan` stops at or faces, and each such pick's anchor (its label, the
/// anchor's label).
fn stops_and_anchors(
    map: &IvlMap,
    plan: &TypedPlan,
    pose: Pose,
) -> (Vec<String>, Vec<(String, String)>) {
    let mut stops: Vec<String> = Vec::new();
    let mut anchored: Vec<(String, String)> = Vec::new();
    for step in &plan.steps {
        for o in step.objects() {
            let Some(t) = picked(plan, o) else {
                if let Object::Name(n) = o {
                    stops.extend(object_label(map, n, pose));
                }
                continue;
            };
            let Some(label) = object_label(map, &t.name, pose) else {
                continue;
            };
            if let Some(Object::Pick(a)) = t.near.as_deref() {
                if let Some(anchor) = object_label(map, &a.name, pose) {
                    anchored.push((label.clone(), anchor));
                }
            }
            stops.push(label);
        }
    }
    (stops, anchored)
}

/// The pick a step's object makes: a pick, or the pick a variable was bound to.
fn picked<'a>(plan: &'a TypedPlan, o: &'a Object) -> Option<&'a Target> {
    match o {
        Object::Pick(t) => Some(t),
        Object::Var(v) => plan.steps.iter().find_map(|s| match s {
            Step::Let { var, target } if var == v => Some(target),
            _ => None,
        }),
        Object::Name(_) | Object::Instance(_) => None,
    }
}

/// How many words after the object it picks out an anchor may be named ("the bench
/// closest to the gold statue": five).
const ANCHOR_WORDS: usize = 6;

/// An object said once, right after the object it picks out, that the plan also stops at:
/// "the lamp by the white bed" planned as the white bed, then the lamp near it
/// (held-out v3, dev: hh03; hi11's "the bench closest to the gold statue"). The plan
/// picks the lamp near the bed (so the bed is the lamp's anchor) and stops at the bed
/// itself, while the person named the bed only once, after the lamp: a re-ask (then a
/// question) whose note says so, never an edit. An anchor named before the object it
/// picks out ("go to the bed, then the lamp next to it") or named twice is a stop the
/// person may have asked for, and is not judged.
fn check_anchor_stops(
    map: &IvlMap,
    instruction: &str,
    plan: &TypedPlan,
    pose: Pose,
) -> Vec<Finding> {
    let w = words(instruction);
    let mentions = object_mentions(map, &w, pose);
    let said_at = |label: &str| -> Vec<usize> {
        mentions
            .iter()
            .filter(|(_, l)| l == label)
            .map(|(k, _)| *k)
            .collect()
    };
    let (stops, anchored) = stops_and_anchors(map, plan, pose);
    let mut out = Vec::new();
    // An object picked near another of its kind that the person named once (held-out
    // v4, dev, hj14: "the stool nearest to you" as the stool nearest the first stool).
    for (label, _) in anchored.iter().filter(|(l, a)| l == a) {
        if said_at(label).len() < 2 {
            let f = Finding::new(
                FindingKind::Word,
                format!("the plan picks a {label} near another {label}, but the person named the {label} once: it is not its own anchor (with no near, distances are from the robot)"),
                format!("which {label} do you mean? there are {}", describe_label(map, label)),
            )
            .about_label(Some(label.clone()));
            if !out.contains(&f) {
                out.push(f);
            }
        }
    }
    for (label, anchor) in anchored {
        let bar = Bar::AnchorStop {
            label: anchor.clone(),
        };
        if anchor == label
            || !stops.contains(&anchor)
            || out.iter().any(|f: &Finding| f.bar.as_ref() == Some(&bar))
        {
            continue;
        }
        let (at_anchor, at_label) = (said_at(&anchor), said_at(&label));
        let Some(&first) = at_label.first() else {
            continue;
        };
        if at_anchor.len() != 1 || at_anchor[0] < first {
            continue;
        }
        // Said to pick it out: the last object named before the anchor is the picked one,
        // at most six words before ("the bench closest to the gold statue"). Held-out v3
        // (dev) hh12: the model picked "the white table nearest to you" near the red
        // stools that the person named twelve words later as a stop of their own.
        let k = at_anchor[0];
        //
        // Not where the words between speak of the robot or go on to the next stop: "the
        // chair nearest to you, then the counter" picks the chair from the robot, and
        // the counter is a stop of its own (held-out v7, dev, hp13 and ho14: right first
        // answers whose `near` was the model's, re-asked to drop the stop and lost).
        match mentions.iter().rfind(|(m, _)| *m < k) {
            Some((m, l))
                if *l == label
                    && k - m <= ANCHOR_WORDS
                    && !w[m + 1..k]
                        .iter()
                        .any(|x| matches!(x.as_str(), "you" | "u" | "me" | "here" | "then")) => {}
            _ => continue,
        }
        out.push(
            Finding::new(
                FindingKind::Word,
                format!("the person named the {anchor} once, after the {label}, to say which {label}: the plan goes to the {label} near the {anchor}, and must not also stop at the {anchor} itself"),
                format!("shall I stop at the {anchor} too, or only at the {label} near it?"),
            )
            .barring(bar),
        );
    }
    // Both stops, neither picked near the other: one clause ([`clauses`]) that names
    // just these two objects, each once in the whole instruction, the second at most
    // six words after the first, nothing between them about the robot or the person,
    // and no "between" (a pair stop). Held-out v16 (dev) va05: "then the saddle display
    // next to the green frame jig" went to the nearest saddle display and then stopped
    // at the frame jig, and no check saw it. On the dev navigation suites, 82 clauses
    // name two objects once each; in two the reference stops at both, each nine words
    // apart or more ("the white hose reel in the appliance bay the red alarm panel").
    // Moves to them or to a side of them (a `face` of the other may be what was asked:
    // "wait at the sofa facing the tv").
    let went: Vec<String> = plan
        .steps
        .iter()
        .filter_map(|s| match s {
            Step::GoTo(o) | Step::Side { object: o, .. } => match (picked(plan, o), o) {
                (Some(t), _) => object_label(map, &t.name, pose),
                (None, Object::Name(n)) => object_label(map, n, pose),
                _ => None,
            },
            _ => None,
        })
        .collect();
    for c in clauses(instruction) {
        if c.iter().any(|x| x == "between") {
            continue;
        }
        let named = object_mentions(map, &c, pose);
        let [(m, label), (k, anchor)] = named.as_slice() else {
            continue;
        };
        let bar = Bar::AnchorStop {
            label: anchor.clone(),
        };
        if label == anchor
            || k - m > ANCHOR_WORDS
            || said_at(label).len() != 1
            || said_at(anchor).len() != 1
            || !went.contains(label)
            || !went.contains(anchor)
            || c[m + 1..*k]
                .iter()
                .any(|x| matches!(x.as_str(), "you" | "u" | "me" | "here"))
            || out.iter().any(|f: &Finding| f.bar.as_ref() == Some(&bar))
        {
            continue;
        }
        out.push(
            Finding::new(
                FindingKind::Word,
                format!("the person named the {anchor} once, right after the {label}, to say which {label} (\"{}\"): pick the {label} with near: the {anchor}, and do not stop at the {anchor} itself", c.join(" ")),
                format!("shall I stop at the {anchor} too, or only at the {label} near it?"),
            )
            .barring(bar),
        );
    }
    out
}

/// How many words after "of" the object a side is said of may be named ("to the left of
/// the big grey fountain": four).
const SIDE_OBJECT_WORDS: usize = 5;

/// A stop at one side of an object that the person asked for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct SideSaid {
    /// The move to that side.
    pub side: Side,
    /// The word that names it ("left", "north").
    pub word: String,
    /// The label of the object it is said of, where the map names one in the words
    /// after "of".
    pub of: Option<String>,
}

/// The side stops the person asks for (design.md: "Where a side is asked for"): a side
/// word that names a move ([`Side::toward`]) followed by "of", "side of" or "hand side
/// of": "stop to the left of the grey fountain", "park on the south side of the green
/// table", "wait on the right hand side of the sofa". Not where the map's name of an
/// object comes right before it ("the chair to the left of the table" says which chair,
/// a relation the library does not hold), and not a turn ("with the bench on your
/// left"), which has no "of".
pub(crate) fn side_moves_said(map: &IvlMap, w: &[String], pose: Pose) -> Vec<SideSaid> {
    let mut out = Vec::new();
    for (i, word) in w.iter().enumerate() {
        let Some(side) = Side::toward(word) else {
            continue;
        };
        let mut j = i + 1;
        for filler in ["hand", "side"] {
            if w.get(j).map(String::as_str) == Some(filler) {
                j += 1;
            }
        }
        if w.get(j).map(String::as_str) != Some("of") {
            continue;
        }
        let mut k = i;
        while k > 0 && matches!(w[k - 1].as_str(), "the" | "to" | "on" | "just") {
            k -= 1;
        }
        if noun_before(map, w, k, pose).is_some() {
            continue;
        }
        let of = (j + 1..(j + 1 + SIDE_OBJECT_WORDS).min(w.len()))
            .find_map(|at| label_at(map, w, at, pose).map(|(_, l, _)| l));
        out.push(SideSaid {
            side,
            word: word.clone(),
            of,
        });
    }
    out
}

/// The labels of the objects the person named once in `instruction` ([`object_mentions`]),
/// as a side stop ([`side_moves_said`]): a plain stop at them is not what was asked.
pub(crate) fn sides_said_of_once(map: &IvlMap, instruction: &str, pose: Pose) -> Vec<String> {
    let w = words(instruction);
    let mentions = object_mentions(map, &w, pose);
    let mut out: Vec<String> = side_moves_said(map, &w, pose)
        .into_iter()
        .filter_map(|s| s.of)
        .filter(|l| mentions.iter().filter(|(_, m)| m == l).count() == 1)
        .collect();
    out.sort();
    out.dedup();
    out
}

/// The first map name the words `w` say ([`name_mentions`]), past a room the robot is
/// already in, said first ([`start_room_named_first`]): what [`side_said_first`] and
/// [`pair_said_first`] hold the plan's first step to.
fn first_name_said(map: &IvlMap, w: &[String], pose: Pose) -> Option<String> {
    let start = start_room_named_first(map, w, pose);
    name_mentions(map, w, pose)
        .into_iter()
        .map(|(_, n)| n)
        .find(|n| Some(n) != start.as_ref())
}

/// The side stop ([`side_moves_said`]) the person asks for at the first map name they
/// say (a room the robot is already in, said first, is skipped:
/// [`start_room_named_first`]), of an object they name only there: "Plant yourself on
/// the north side of the white dispatch desk. Then the gear locker, ..." is
/// `(Side::North, "dispatch desk")`, so the plan's first step is that side move
/// (`Vocabulary::first_side`). `None` where the first name is a room, an object with no
/// side said of it, or one named again.
pub(crate) fn side_said_first(
    map: &IvlMap,
    instruction: &str,
    pose: Pose,
) -> Option<(Side, String)> {
    let w = words(instruction);
    let first = first_name_said(map, &w, pose)?;
    if !sides_said_of_once(map, instruction, pose).contains(&first) {
        return None;
    }
    side_moves_said(map, &w, pose)
        .into_iter()
        .find(|s| s.of.as_ref() == Some(&first))
        .map(|s| (s.side, first))
}

/// The object the person asks to stop between two of ([`pairs_said_between`]: "the gap
/// between the two pink party tables", named only there) where that is the first map
/// name they say (a room the robot is already in, said first, is skipped:
/// [`start_room_named_first`]): the plan's first step is then `move_between_the_two` of
/// it (`Vocabulary::first_side`), as [`side_said_first`]'s is a side move.
pub(crate) fn pair_said_first(map: &IvlMap, instruction: &str, pose: Pose) -> Option<String> {
    let first = first_name_said(map, &words(instruction), pose)?;
    let first = object_label(map, &first, pose)?;
    pairs_said_between(map, instruction, pose)
        .contains(&first)
        .then_some(first)
}

/// The label of the object a step's argument stands for, where it names one.
fn step_object_label(map: &IvlMap, plan: &TypedPlan, o: &Object, pose: Pose) -> Option<String> {
    match (picked(plan, o), o) {
        (Some(t), _) => object_label(map, &t.name, pose),
        (None, Object::Name(n)) => object_label(map, n, pose),
        (None, Object::Instance(id)) => map.instance_by_id(*id).map(|i| i.label.clone()),
        (None, Object::Pick(_) | Object::Var(_)) => None,
    }
}

/// A side stop the person asked for ([`side_moves_said`]) that the plan does not make:
/// no move to that side of an object of that name (held-out v9, dev: "pull up to the
/// right of the blue teller desk" and "stop on the left of the grey fountain" planned as
/// stops at the desk and the fountain, which no check saw). A re-ask (then a question)
/// naming the words, never an edit.
fn check_side_moves(map: &IvlMap, instruction: &str, plan: &TypedPlan, pose: Pose) -> Vec<Finding> {
    let w = words(instruction);
    let mut out = Vec::new();
    for said in side_moves_said(map, &w, pose) {
        let made = plan.steps.iter().any(|s| match s {
            Step::Side { side, object } if *side == said.side => {
                match (&said.of, step_object_label(map, plan, object, pose)) {
                    (Some(of), Some(label)) => *of == label,
                    _ => true,
                }
            }
            _ => false,
        });
        if made {
            continue;
        }
        let f = said.side.function();
        let word = &said.word;
        let (what, to_user) = match &said.of {
            Some(of) => (
                format!("{word} of the {of}"),
                format!("shall I stop on the {word} side of the {of}, or at the {of} itself?"),
            ),
            None => (
                format!("{word} of"),
                format!("which object shall I stop on the {word} side of?"),
            ),
        };
        let mut finding = Finding::new(
            FindingKind::Word,
            format!("the person asked to stop {what}, but the plan never calls {f}: for that stop write {f}(...) with the object, in place of move_to_object"),
            to_user,
        );
        if let Some(of) = &said.of {
            finding = finding.barring(Bar::SideStop {
                label: of.clone(),
                side: said.side,
            });
        }
        if !out.contains(&finding) {
            out.push(finding);
        }
    }
    out
}

/// Picks near an object the person never named, by a name or a synonym of it or a typo
/// of one ("the cabinet nearest to you" as the cabinet `near: get_obj("workbench")`:
/// held-out v7, dev, hq13, a wrong plan no check saw), or named only in another clause
/// than the picked object ([`anchors_said`]: "whichever sofa is nearest to you, then
/// pull up to the right of the blue teller desk" as the sofa near the teller desk).
/// Outside a conversation, where an earlier instruction may have named it. The object
/// itself as its anchor is [`check_anchor_stops`]'s.
fn check_unsaid_anchors(
    map: &IvlMap,
    instruction: &str,
    plan: &TypedPlan,
    pose: Pose,
) -> Vec<Finding> {
    let w = words(instruction);
    let said: Vec<String> = (0..w.len())
        .filter_map(|k| {
            label_at(map, &w, k, pose)
                .map(|(_, l, _)| l)
                .or_else(|| typed_label_at(map, &w, k).map(|(_, l)| l))
        })
        .collect();
    let clauses = anchors_said(map, instruction, pose);
    let mut out: Vec<Finding> = Vec::new();
    for t in targets(plan) {
        let Some(Object::Pick(a)) = t.near.as_deref() else {
            continue;
        };
        let (Some(label), Some(anchor)) = (
            object_label(map, &t.name, pose),
            object_label(map, &a.name, pose),
        ) else {
            continue;
        };
        let to_model = if !said.contains(&anchor) {
            format!("the plan picks the {label} near a {anchor}, but the person named no {anchor}: give near only an object the person named (with no near, distances are from the robot)")
        } else if label != anchor
            && said.contains(&label)
            && !clauses
                .iter()
                .any(|(l, anchors)| *l == label && anchors.contains(&anchor))
        {
            format!("the plan picks the {label} near the {anchor}, but the person did not say the {label} is near the {anchor}: give near only an object said with it (\"the {label} closest to the ...\"); with no near, distances are from the robot")
        } else {
            continue;
        };
        let f = Finding::new(
            FindingKind::Word,
            to_model,
            format!(
                "which {label} do you mean? there are {}",
                describe_label(map, &label)
            ),
        )
        .about_label(Some(label.clone()));
        if !out.contains(&f) {
            out.push(f);
        }
    }
    out
}

/// Everything found in `plan` and `tuples` for `instruction` on `map`. `visited` holds
/// the instances the plan's dry run stopped at (empty without a dry run): a colour is
/// accounted for when a target says it or when the plan reaches an instance of it ("the
/// sofa that isn't black" on a map of one red and one black sofa is "the red sofa").
/// `refs` are the instances the conversation visited before (empty outside one).
#[must_use]
pub fn check_answer(
    map: &IvlMap,
    instruction: &str,
    tuples: &[Tuple],
    plan: &TypedPlan,
    pose: Pose,
    visited: &[u32],
    refs: &[u32],
) -> Vec<Finding> {
    check_answer_after(
        map,
        instruction,
        None,
        tuples,
        plan,
        pose,
        visited,
        visited,
        refs,
    )
}

/// [`check_answer`] for an instruction that may answer an `earlier` one, which got a
/// question or a refusal instead of a plan (`PlanContext::earlier`), with the instances
/// the dry run's selections picked (`picked`; [`check_answer`] takes those it stopped
/// at): the earlier words
/// count as said for what a plan may select on (colours, counts, orders, rooms), never
/// as asked for, so what the person asks is still read from `instruction` alone.
#[must_use]
#[allow(clippy::too_many_arguments)] // check_answer's, and the one instruction before
pub fn check_answer_after(
    map: &IvlMap,
    instruction: &str,
    earlier: Option<&str>,
    tuples: &[Tuple],
    plan: &TypedPlan,
    pose: Pose,
    visited: &[u32],
    picked: &[u32],
    refs: &[u32],
) -> Vec<Finding> {
    let mut out = check_tuples(map, instruction, tuples, plan, pose, visited, refs);
    out.extend(check_names(map, instruction, plan, pose, visited, refs));
    out.extend(check_words(map, instruction, plan, pose, visited, picked));
    out.extend(check_two_guessed(map, instruction, plan, pose));
    out.extend(check_visits(map, instruction, pose, visited, refs));
    out.extend(check_anchor_stops(map, instruction, plan, pose));
    out.extend(check_side_moves(map, instruction, plan, pose));
    out.extend(check_excluded_colours_kept(map, instruction, plan, pose));
    if refs.is_empty() && earlier.is_none() {
        out.extend(check_unnamed_stops(map, instruction, plan, pose));
        out.extend(check_names_said_again(map, instruction, plan, pose));
        out.extend(check_listed_counts_unplanned(
            map,
            instruction,
            tuples,
            plan,
            pose,
        ));
        out.extend(check_unsaid_anchors(map, instruction, plan, pose));
        out.extend(check_colours_of_others(map, instruction, plan, pose));
    }
    if return_said_on(
        map,
        instruction,
        pose,
        !refs.is_empty() || earlier.is_some(),
    ) && !plan_returns(plan)
    {
        let to_model = if refs.is_empty() {
            "the person asked to come back to where you began, but the plan never moves back: write move_to_start(); where their words say to come back"
        } else {
            "the person asked to come back, but the plan never moves back: write move_to_start(); for where this instruction began, or move_to([x, y]) with the position where we started, where their words say to come back"
        };
        out.push(Finding::new(
            FindingKind::Word,
            to_model,
            "should I come back to where I started, and when?",
        ));
    }
    if between_said(instruction) && !plan_stops_between(plan) {
        let f = Finding::new(
            FindingKind::Word,
            "the person said \"between\", but the plan stops between nothing: write move_in_between(a, b) for between two objects, or move_between_the_two(name, ...) for between the two of one kind",
            "between what shall I stop?",
        );
        // "Between the two white folding tables", the one time they are named: the
        // finding is at the picks of that object, and the re-ask's continuation stops
        // between the two there.
        // "Between the pink anchor and the orange buoy": the finding is at the first
        // pick of the object named first after "between", so that the re-ask keeps the
        // steps before it. Held-out v16 (dev) vc10: about no step, the re-ask wrote the
        // whole plan again and lost the side stop that the steps before had right.
        out.push(
            match pairs_said_between(map, instruction, pose).as_slice() {
                [label] => f.barring(Bar::PairStop {
                    label: label.clone(),
                }),
                _ => f.about_label(first_named_between(map, instruction, pose)),
            },
        );
    }
    if refs.is_empty() && earlier.is_none() {
        out.extend(pairs_unsaid(map, instruction, plan, pose));
    }
    let known = known_colours(map, refs, earlier);
    let allowed = said_before(instruction, earlier);
    out.extend(check_unsaid_colours(map, &allowed, &known, plan, pose));
    let in_chat = !refs.is_empty();
    // What a selection may say only when the person's words do: each with the re-ask's
    // note and the question's words after "which <name> do you mean".
    let directions = |t: &Target| {
        format!("the plan counts the {} in order \"{}\", but the person named no direction: leave the order out (nearest first) unless their words give one", t.name, t.order.name())
    };
    let sizes = |t: &Target| {
        format!("the plan counts the {} in order \"{}\", but the person said nothing of size: leave the order out (nearest first) unless their words give one", t.name, t.order.name())
    };
    let far_ends = |t: &Target| {
        format!("the plan counts the {} in order \"far_to_near\", but the person said nothing of the far end: leave the order out (nearest first) unless their words count from far away", t.name)
    };
    let regions = |t: &Target| {
        let region = t.region.as_deref().unwrap_or_default();
        format!("the plan picks the {} in the {region}, but the person did not name the {region}: leave the region out unless their words put it in a room", t.name)
    };
    let ordinals = |t: &Target| {
        format!("the plan picks the {} with ordinal {}, but the person said no such count: leave the ordinal out unless their words count (\"the third\", \"number 3\", \"second to last\")", t.name, t.ordinal)
    };
    let excluding = exclusion_said(&allowed);
    let exclusions = |t: &Target| {
        let c = t.not_colour.as_deref().unwrap_or_default();
        let what = if excluding {
            format!("did not exclude {c}")
        } else {
            "excluded nothing".to_string()
        };
        format!("the plan picks the {} that is not {c}, but the person {what}: leave not_colour out unless their words exclude a colour (\"not\", \"isn't\", \"other than\")", t.name)
    };
    // Outside a conversation, where a direction is said of some objects only.
    let said_of_kind = |what| {
        (refs.is_empty() && earlier.is_none())
            .then(|| said_of_map(map, instruction, pose, what))
            .flatten()
    };
    let others_of = |said: &Option<Vec<String>>, what| {
        said_of_others(said.as_deref(), what, plan, |n| object_label(map, n, pose))
    };
    let directed = said_of_kind(SaidOf::Direction);
    let others = |t: &Target| {
        let of = directed.as_deref().unwrap_or_default().join(", the ");
        format!("the plan counts the {} in order \"{}\", but the person named a direction only for the {of}: leave the {}'s order out (nearest first) unless their words about it give one", t.name, t.order.name(), t.name)
    };
    let counted = said_of_kind(SaidOf::Count);
    let counts_of_others = |t: &Target| {
        let of = counted.as_deref().unwrap_or_default().join(", the ");
        format!("the plan picks the {} with ordinal {}, but the person said a count only of the {of}: leave the {}'s ordinal out unless their words about it count", t.name, t.ordinal, t.name)
    };
    let far_ended = said_of_kind(SaidOf::FarEnd);
    let far_ends_of_others = |t: &Target| {
        let of = far_ended.as_deref().unwrap_or_default().join(", the ");
        if t.order == ObjectOrder::FarToNear {
            format!("the plan counts the {} in order \"far_to_near\", but the person spoke of the far end only for the {of}: leave the {}'s order out (nearest first) unless their words about it count from far away", t.name, t.name)
        } else {
            format!("the plan picks the {} with ordinal {}, counted from the far end, but the person spoke of the far end only for the {of}: leave the {}'s ordinal out (nearest first) unless their words about it count from far away", t.name, t.ordinal, t.name)
        }
    };
    let name_words = object_name_words(map);
    let unsaid: [(Vec<&Target>, &Note<'_>, &str); 9] = [
        (
            unsaid_directions(&allowed, plan),
            &directions,
            ", counting from where",
        ),
        (unsaid_sizes(&allowed, Some(&name_words), plan), &sizes, ""),
        (unsaid_far_ends(&allowed, plan), &far_ends, ""),
        (
            unsaid_regions(&allowed, &name_words, in_chat, plan),
            &regions,
            "",
        ),
        (unsaid_ordinals(&allowed, plan), &ordinals, ""),
        (
            unsaid_exclusions(&allowed, &known, in_chat, plan),
            &exclusions,
            "",
        ),
        (
            others_of(&directed, SaidOf::Direction),
            &others,
            ", counting from where",
        ),
        (others_of(&counted, SaidOf::Count), &counts_of_others, ""),
        (
            others_of(&far_ended, SaidOf::FarEnd),
            &far_ends_of_others,
            "",
        ),
    ];
    for (targets, to_model, how) in unsaid {
        out.extend(unsaid_findings(map, pose, plan, targets, to_model, |t| {
            format!("which {} do you mean{how}", t.name)
        }));
    }
    out.extend(unsaid_findings(
        map,
        pose,
        plan,
        counted_from_the_end(plan),
        |t| {
            let k = t.ordinal.unsigned_abs();
            match t.order.reversed() {
                ObjectOrder::NearToFar => format!("the plan picks the {} with ordinal {} in order \"far_to_near\", which counts from the near end: write ordinal: {k} (nearest first) for that, or ordinal: {} alone for the farthest", t.name, t.ordinal, t.ordinal),
                o => format!("the plan picks the {} with ordinal {} in order \"{}\": write ordinal: {k} with order \"{}\" for that", t.name, t.ordinal, t.order.name(), o.name()),
            }
        },
        |t| format!("which {} do you mean", t.name),
    ));
    // A plan with no step that moves or turns does nothing the person asked for.
    if !plan
        .steps
        .iter()
        .any(|s| !matches!(s, Step::Let { .. } | Step::Say(_)))
    {
        out.push(Finding::new(
            FindingKind::Parts,
            "the plan does not move the robot",
            "what should I do?",
        ));
    }
    out
}

/// A dry-run or query error as a finding: the person's side of it is the error itself
/// ("there are 2 yellow tables; asked for the 3rd").
#[must_use]
pub fn runtime_finding(message: &str, line: Option<&str>) -> Finding {
    Finding::new(
        FindingKind::Runtime,
        format!(
            "running the plan fails: {message}{}",
            line.map(|l| format!(" (in `{}`)", l.trim()))
                .unwrap_or_default()
        ),
        message.to_string(),
    )
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::v2::answer::parse_answer;

    /// flat-a, the map the checks' tests (and the grammar narrowing's) run on.
    pub(crate) fn map() -> IvlMap {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/scenes/flat-a.scene.json"
        );
        IvlMap::from_scene(&map_core::scene::Scene::from_path(path).unwrap())
    }

    #[test]
    fn a_direction_is_said_of_the_objects_named_where_it_is_said() {
        let of = |instruction: &str, line: &str| {
            directions_said_of(instruction, &crate::tuples::parse_tuples(line).unwrap())
        };
        assert_eq!(
            of(
                "the westernmost oil drum and then the engine shed",
                "[(oil drum, None, None), (engine shed, None, None)]"
            ),
            Some(vec!["oil drum".to_string()])
        );
        // A clause that names none: the nearest that does.
        assert_eq!(
            of(
                "of the ball returns, the one furthest west, then the pro shop",
                "[(ball return, None, None), (pro shop, None, None)]"
            ),
            Some(vec!["ball return".to_string(), "pro shop".to_string()])
        );
        assert_eq!(of("the oil drum", "[(oil drum, None, None)]"), None);
        assert_eq!(
            of("the westernmost oil drum", "[(engine shed, None, None)]"),
            None
        );
    }

    #[test]
    fn a_name_listed_with_fewer_words_than_said_is_found() {
        let cut = |instruction: &str, line: &str| -> Vec<String> {
            names_cut(instruction, &crate::tuples::parse_tuples(line).unwrap())
                .into_iter()
                .map(|n| format!("{}/{}/{}", n.said, n.listed, n.index))
                .collect()
        };
        // A word before the name, after an article, a count or a superlative.
        assert_eq!(
            cut("the third waiting bench", "[(bench, 3, None)]"),
            ["waiting bench/bench/0"]
        );
        assert_eq!(
            cut(
                "the last dog kennel counting from the west, then the waiting bench that's green",
                "[(kennel, last, None), (bench, None, green)]"
            ),
            ["dog kennel/kennel/0", "waiting bench/bench/1"]
        );
        assert_eq!(
            cut(
                "the northernmost treatment trolley",
                "[(trolley, 1, None, north_to_south)]"
            ),
            ["treatment trolley/trolley/0"]
        );
        // A word of another object's name, said here apart from that name (held-out
        // v13, dev, nx34).
        assert_eq!(
            cut(
                "the wax bench closest to the red wax heater",
                "[(bench, None, red), (wax heater, None, red)]"
            ),
            ["wax bench/bench/0"]
        );
        assert_eq!(
            cut(
                "the wax heater, then the wax bench",
                "[(wax heater, None, None), (bench, None, None)]"
            ),
            ["wax bench/bench/1"]
        );
        // A two-word object is taken whole (held-out v15, dev, rx18 and rx19).
        for (instruction, line) in [
            (
                "the tank dolly sitting closest to the orange coral tank",
                "[(tank dolly, None, None), (coral tank, None, orange)]",
            ),
            (
                "the one-from-the-end viewing seat as you go from west to east",
                "[(viewing seat, 2, None, east_to_west)]",
            ),
        ] {
            assert!(cut(instruction, line).is_empty(), "{instruction}");
        }
        // A word after it, followed by how it is counted or placed (a plural said).
        assert_eq!(
            cut(
                "take me to the fourth ball return from the east",
                "[(ball, 4, None)]"
            ),
            ["ball return/ball/0"]
        );
        assert_eq!(
            cut(
                "the ball returns counting from the west",
                "[(ball, None, None)]"
            ),
            ["ball return/ball/0"]
        );
        // The whole name listed; a colour, a count, a courtesy, a verb or another
        // object's word beside it; a typo of a count; a spaced dash; no article before.
        for (instruction, line) in [
            ("the oak barrel", "[(oak barrel, None, None)]"),
            ("go to the chair painted red", "[(chair, None, red)]"),
            (
                "the westernmost white freezer plz",
                "[(freezer, 1, white, west_to_east)]",
            ),
            (
                "go to the thrid table from the north",
                "[(table, 3, None, north_to_south)]",
            ),
            (
                "the big chair near the sofa",
                "[(chair, None, None), (sofa, None, None)]",
            ),
            (
                "there are a few booth seats - pick the blue one",
                "[(booth seat, None, blue)]",
            ),
            (
                "the mash tun - stand on its west side",
                "[(mash tun, None, None)]",
            ),
            ("visit oak barrel", "[(barrel, None, None)]"),
            (
                "the sofa chair, then the chair",
                "[(sofa, None, None), (chair, None, None)]",
            ),
            (
                "the crate next to the blue cabinet checked",
                "[(crate, None, None), (cabinet, None, blue)]",
            ),
        ] {
            assert!(cut(instruction, line).is_empty(), "{instruction}");
        }
    }

    /// The cases of the extraction suites of `versions` ("" the first, "2" held-out v2,
    /// ...): each with its suite's file name, id, instruction and expected tuples.
    fn extraction_cases(versions: &[&str]) -> Vec<(String, String, String, Vec<Tuple>)> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/suites");
        let mut out = Vec::new();
        for v in versions {
            let name = if v.is_empty() {
                "extract.extract.jsonl".to_string()
            } else {
                format!("heldout{v}.extract.jsonl")
            };
            let text = std::fs::read_to_string(dir.join(&name)).unwrap();
            for line in text.lines().filter(|l| !l.trim().is_empty()) {
                let case: serde_json::Value = serde_json::from_str(line).unwrap();
                let tuples: Vec<Tuple> = serde_json::from_value(case["expected"].clone()).unwrap();
                out.push((
                    name.clone(),
                    case["id"].to_string(),
                    case["instruction"].as_str().unwrap().to_string(),
                    tuples,
                ));
            }
        }
        out
    }

    /// No `expected` answer of the extraction suites written before held-out v13 reads
    /// as a name cut short ([`names_cut`]): each is what a right answer lists.
    #[test]
    fn no_right_answer_of_the_earlier_extraction_suites_is_a_name_cut_short() {
        let cases = extraction_cases(&["", "2", "3", "4", "7", "8", "9", "10", "11", "12"]);
        assert_eq!(cases.len(), 565);
        for (name, id, instruction, expected) in cases {
            // Only the names are judged, each as the suite spells it.
            let tuples: Vec<Tuple> = expected
                .into_iter()
                .map(|t| Tuple {
                    object: t.object,
                    ordinal: None,
                    colour: None,
                    order: None,
                })
                .collect();
            let found = names_cut(&instruction, &tuples);
            assert!(found.is_empty(), "{name} {id}: {found:?}");
        }
    }

    /// No `expected` answer of the dev extraction suites (held-out v13 too, dev since
    /// its third run) lacks an order the person counted in ([`orders_unlisted`]).
    #[test]
    fn no_right_answer_of_the_dev_extraction_suites_lacks_an_order_said() {
        let cases = extraction_cases(&["", "2", "3", "4", "7", "8", "9", "10", "11", "12", "13"]);
        assert_eq!(cases.len(), 615);
        let found_in: Vec<String> = cases
            .into_iter()
            .filter(|(_, _, instruction, tuples)| !orders_unlisted(instruction, tuples).is_empty())
            .map(|(name, id, _, _)| format!("{name} {id}"))
            .collect();
        // x26, "the sixth chair from the left", is of the first suite, which lists no
        // orders (formats.md: suites may leave them out).
        assert_eq!(found_in, ["extract.extract.jsonl \"x26\""]);
    }

    #[test]
    fn a_place_said_of_an_object_and_listed_by_no_tuple_is_found() {
        let unlisted = |instruction: &str, line: &str| -> Vec<String> {
            places_unlisted(instruction, &crate::tuples::parse_tuples(line).unwrap())
                .into_iter()
                .map(|p| format!("{}/{}/{}", p.phrase, p.word, p.after))
                .collect()
        };
        assert_eq!(
            unlisted(
                "helmet rack in the kit room, please and thank you",
                "[(helmet rack, None, None)]"
            ),
            ["in the kit room/kit/1"]
        );
        assert_eq!(
            unlisted(
                "the till in the snack bar, then the bridge",
                "[(till, None, None), (bridge, None, None)]"
            ),
            ["in the snack bar/snack/1"]
        );
        assert_eq!(
            unlisted(
                "the luggage rack on the red car deck",
                "[(luggage rack, None, None)]"
            ),
            ["on the red car deck/car/1"]
        );
        // Listed (a plural said, a singular listed), or no place.
        for (instruction, line) in [
            (
                "the till in the snack bar",
                "[(till, None, None), (snack bar, None, None)]",
            ),
            (
                "the chair in the offices",
                "[(chair, None, None), (office, None, None)]",
            ),
            ("stop on the west side of the desk", "[(desk, None, None)]"),
            (
                "ease in on the left of the blue seat",
                "[(seat, None, blue)]",
            ),
            (
                "stop in the middle of the two desks",
                "[(desk, None, None)]",
            ),
            (
                "the chair in the far corner of the hall",
                "[(chair, None, None), (hall, None, None)]",
            ),
            ("turn around", "[]"),
        ] {
            assert!(unlisted(instruction, line).is_empty(), "{instruction}");
        }
    }

    #[test]
    fn a_stop_between_the_two_of_a_name_said_once_is_read() {
        let m = map();
        let pose = m.start_pose;
        let said = |s: &str| pairs_said_between(&m, s, pose);
        assert_eq!(
            said("stop between the two yellow tables, then the fridge"),
            ["table"]
        );
        assert_eq!(
            said("Waypoint 1: the gap between the two yellow tables."),
            ["table"]
        );
        assert_eq!(
            said("go to the fridge, then halfway between both couches"),
            ["sofa"]
        );
        for not in [
            "stop between the two red chairs, then the black chair",
            "stop between the sofa and the two chairs",
            "stop between the red sofa and the black one",
            "go to the two tables",
            "stop between the two tables and the sofa, then the table by the tv",
        ] {
            assert!(said(not).is_empty(), "{not}");
        }
    }

    #[test]
    fn the_two_of_a_name_said_only_once_is_found() {
        let pair = |f: &[Finding]| f.iter().any(|x| x.to_model.contains("the two sofas"));
        // Two objects named, one of them a sofa: a stop between two objects.
        let f = findings(
            "stop between the red sofa and the black table",
            "objects: [(sofa, None, red), (table, None, black)]\nplan:\nmove_between_the_two(\"sofa\");",
        );
        assert!(pair(&f), "{f:?}");
        assert!(f
            .iter()
            .any(|x| x.to_user == "between which two objects shall I stop?"));
        // "The two sofas", or "couches" for them: the pair.
        for said in ["stop between the two sofas", "stop between the couches"] {
            let f = findings(
                said,
                "objects: [(sofa, None, None)]\nplan:\nmove_between_the_two(\"sofa\");",
            );
            assert!(!pair(&f), "{said}: {f:?}");
        }
    }

    #[test]
    fn names_said_in_the_plural() {
        let names: Vec<String> = ["costume rack", "shelf", "chair", "rack", "piano"]
            .iter()
            .map(|s| (*s).to_string())
            .collect();
        let said = |i: &str| -> Vec<&str> {
            said_in_plural(&names, i)
                .into_iter()
                .map(String::as_str)
                .collect()
        };
        assert_eq!(
            said("between the two Costume Racks"),
            ["costume rack", "rack"]
        );
        assert_eq!(said("go between the shelves, then the chair"), ["shelf"]);
        assert!(said("between the piano and the black microphone").is_empty());
        assert!(said("the chair, then the costume rack").is_empty());
    }

    fn findings(instruction: &str, answer: &str) -> Vec<Finding> {
        let m = map();
        let a = parse_answer(answer).unwrap();
        check_answer(&m, instruction, &a.tuples, &a.plan, m.start_pose, &[], &[])
    }

    #[test]
    fn a_finding_is_placed_at_the_first_step_it_is_about() {
        let m = map();
        let first = |instruction: &str, answer: &str| {
            let a = parse_answer(answer).unwrap();
            let f = check_answer(&m, instruction, &a.tuples, &a.plan, m.start_pose, &[], &[]);
            assert!(!f.is_empty(), "{instruction}: no finding");
            first_disputed_step(&m, instruction, &f, &a.plan, m.start_pose)
        };
        // A colour dropped from the sofa, the second step: the kitchen before it stands.
        let sofa = "objects: [(kitchen, None, None), (sofa, None, black)]\nplan:\nmove_to_object(\"kitchen\");\nmove_to_object(get_obj(\"sofa\"));";
        assert_eq!(first("the kitchen, then the black sofa", sofa), Some(1));
        // A synonym's pick is of its label ("couch" is a sofa).
        let couch = "objects: [(kitchen, None, None), (couch, None, black)]\nplan:\nmove_to_object(\"kitchen\");\nmove_to_object(get_obj(\"couch\"));";
        assert_eq!(first("the kitchen, then the black couch", couch), Some(1));
        // An unsaid count on the first step.
        let chair = "objects: [(chair, None, None), (kitchen, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 2}));\nmove_to_object(\"kitchen\");";
        assert_eq!(first("the chair, then the kitchen", chair), Some(0));
        // Something the plan lacks is in no step: no step is agreed.
        let no_return = "objects: [(kitchen, None, None)]\nplan:\nmove_to_object(\"kitchen\");";
        assert_eq!(first("the kitchen and come back here", no_return), None);
        // A colour said of an object the plan never picks: placed as the object the plan
        // lacks, after the steps for what was named before it (held-out v10, dev, ka05):
        // the sofa, said alone in its clause, after the chair and the kitchen; said with
        // the kitchen, in place of the kitchen's step.
        let no_sofa = "objects: [(chair, None, None), (kitchen, None, None), (sofa, None, black), (table, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\"));\nmove_to_object(\"kitchen\");\nmove_to_object(get_obj(\"table\"));";
        assert_eq!(
            first(
                "the chair, then the kitchen, then the black sofa, then the table",
                no_sofa
            ),
            Some(2)
        );
        assert_eq!(
            first(
                "the chair, then in the kitchen the black sofa, then the table",
                no_sofa
            ),
            Some(1)
        );
        // A finding of the objects line is of no step.
        let a = parse_answer(sofa).unwrap();
        let parts = Finding::new(FindingKind::Parts, "", "").about_label(Some("sofa".into()));
        assert_eq!(
            first_disputed_step(&m, "", &[parts], &a.plan, m.start_pose),
            None
        );
        // The dry run's step, and the earliest of several places.
        let run = runtime_finding("no such sofa", None).at_step(1);
        let word = Finding::new(FindingKind::Word, "", "").about_label(Some("kitchen".into()));
        assert_eq!(
            first_disputed_step(&m, "", std::slice::from_ref(&run), &a.plan, m.start_pose),
            Some(1)
        );
        assert_eq!(
            first_disputed_step(&m, "", &[run, word], &a.plan, m.start_pose),
            Some(0)
        );
        // An object the plan lacks: the steps for what was named before it stand, in the
        // order named, less the last where the missing one is said with it (the kitchen
        // of "the chair in the kitchen": the table stands; the chair may be where the
        // kitchen was meant to go) ...
        let no_kitchen = "objects: [(table, None, None), (chair, None, None), (kitchen, None, None)]\nplan:\nmove_to_object(get_obj(\"table\"));\nmove_to_object(get_obj(\"chair\"));\nmove_to_object(get_obj(\"sofa\"));";
        assert_eq!(
            first("the table, then the chair in the kitchen", no_kitchen),
            Some(1)
        );
        // ... and all of them where its clause names it alone (held-out v12, dev, ma02:
        // "..., then a ball rack other than the green one, and call it a day in the pro
        // shop" kept the booth seat and the claw machine, and the re-ask wrote the ball
        // rack again and no pro shop, three times).
        assert_eq!(
            first("the table, then the chair, then the kitchen", no_kitchen),
            Some(2)
        );
        assert_eq!(
            first(
                "the table, then the chair, and stop in the kitchen",
                no_kitchen
            ),
            Some(2)
        );
        // Named out of the plan's order: nothing stands.
        assert_eq!(
            first("the chair, then the table, then the kitchen", no_kitchen),
            Some(0)
        );
        // A stop of its own where the steps before it stand for what was named before
        // it, and only there (held-out v12, dev, mb02: "..., and end the run in the
        // bottling room" is no next stop after a plan that went astray at its second).
        let stop = |instruction: &str| {
            let a = parse_answer(no_kitchen).unwrap();
            let f = check_answer(&m, instruction, &a.tuples, &a.plan, m.start_pose, &[], &[]);
            disputed_places(&m, instruction, &f, &a.plan, m.start_pose)
                .unwrap()
                .into_iter()
                .find(|p| p.lacking)
                .map(|p| (p.at, p.stop))
        };
        assert_eq!(
            stop("the table, then the chair, then the kitchen"),
            Some((2, Some("kitchen".to_string())))
        );
        assert_eq!(
            stop("the table, then the chair in the kitchen"),
            Some((1, None))
        );
        assert_eq!(
            stop("the chair, then the table, then the kitchen"),
            Some((0, None))
        );
        // The room the robot is in, said first, is no stop the steps stand for (held-out
        // v15, dev, rc04's form; flat-a starts in the living room).
        assert_eq!(
            stop("We're in the living room. The table, then the chair, then the kitchen"),
            Some((2, Some("kitchen".to_string())))
        );
        // A missing anchor said with the first stop: nothing stands.
        let no_anchor = "objects: [(chair, None, None), (kitchen, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\"));\nmove_to_object(\"kitchen\");";
        assert_eq!(
            first("the chair closest to the sofa, then the kitchen", no_anchor),
            Some(0)
        );
        // A synonym and a room picked with `region:` are named as said ("the telly",
        // "the table in the kitchen"): all three stand, and the bed, said alone, goes
        // after them.
        let tv = "objects: [(telly, None, None), (table, None, None), (chair, None, None), (bed, None, None)]\nplan:\nmove_to_object(get_obj(\"tv\"));\nmove_to_object(get_obj(\"table\", #{region: \"kitchen\"}));\nmove_to_object(get_obj(\"chair\"));\nmove_to_object(get_obj(\"sofa\"));";
        assert_eq!(
            first(
                "the telly, the table in the kitchen, the chair, then the bed",
                tv
            ),
            Some(3)
        );
        // A finding about one pick is at its step, not at an earlier pick of its label:
        // an unsaid colour on the second chair keeps the first chair and the sofa.
        let chairs = "objects: [(chair, None, None), (sofa, None, red), (chair, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\"));\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));\nmove_to_object(get_obj(\"chair\", #{colour: \"black\"}));";
        assert_eq!(
            first("the chair, then the red sofa, then another chair", chairs),
            Some(2)
        );
        // The same note on two picks: the earlier stands for both.
        let both = "objects: [(chair, None, None), (sofa, None, red), (chair, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 2}));\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));\nmove_to_object(get_obj(\"chair\", #{ordinal: 2}));";
        assert_eq!(
            first("the chair, then the red sofa, then another chair", both),
            Some(0)
        );
        // A step past the plan's end is no place in it.
        let past = runtime_finding("x", None).at_step(5);
        assert_eq!(
            first_disputed_step(&m, "", &[past], &a.plan, m.start_pose),
            None
        );
    }

    #[test]
    fn a_colour_said_only_of_another_object_is_a_finding_on_the_pick_that_takes_it() {
        let of_others = |instruction: &str, answer: &str| {
            findings(instruction, answer)
                .into_iter()
                .filter(|f| f.to_model.contains("not of the"))
                .collect::<Vec<_>>()
        };
        // "the table next to the black sofa": black is the sofa's.
        let said = "the table closest to the black sofa, then the chair";
        let wrong = "objects: [(table, None, None), (chair, None, None)]\nplan:\nmove_to_object(get_obj(\"table\", #{near: get_obj(\"sofa\", #{colour: \"black\"})}));\nmove_to_object(get_obj(\"chair\", #{colour: \"black\"}));";
        let f = of_others(said, wrong);
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(
            f[0].to_model.contains("the chair with colour \"black\""),
            "{f:?}"
        );
        assert_eq!(
            f[0].bar,
            Some(Bar::UnsaidColours {
                label: "chair".into()
            })
        );
        // At the chair's step (the pick that takes it).
        assert_eq!(f[0].about, Some(About::Step(1)));
        // Excluding it is taking it too.
        let excluded = wrong.replace(
            "get_obj(\"chair\", #{colour:",
            "get_obj(\"chair\", #{not_colour:",
        );
        assert_eq!(of_others(said, &excluded).len(), 1);
        // The sofa's own colour, and a chair with none: nothing.
        let right = "objects: [(table, None, None), (chair, None, None)]\nplan:\nmove_to_object(get_obj(\"table\", #{near: get_obj(\"sofa\", #{colour: \"black\"})}));\nmove_to_object(get_obj(\"chair\"));";
        assert!(of_others(said, right).is_empty());
        // Said of the chair too, or once after a name ("the chair that's black"): not judged.
        assert!(of_others(
            "the table closest to the black sofa, then the black chair",
            wrong
        )
        .is_empty());
        assert!(of_others(
            "the table closest to the black sofa, then the chair that's black",
            wrong
        )
        .is_empty());
        // A synonym is its label's ("the black couch").
        assert_eq!(
            of_others(
                "the table closest to the black couch, then the chair",
                wrong
            )
            .len(),
            1
        );
    }

    /// The findings for a plan of one move to `object` picked with `select`.
    fn findings_for_pick(instruction: &str, object: &str, select: &str) -> Vec<Finding> {
        findings(
            instruction,
            &format!("objects: [({object}, None, None)]\nplan:\nmove_to_object(get_obj(\"{object}\", {select}));"),
        )
    }

    /// Asserts that the pick of [`findings_for_pick`] gets no finding saying `says`.
    fn assert_no_finding(instruction: &str, object: &str, select: &str, says: &str) {
        let f = findings_for_pick(instruction, object, select);
        assert!(
            f.iter().all(|x| !x.to_model.contains(says)),
            "{instruction}: {f:?}"
        );
    }

    /// Asserts that the pick of [`findings_for_pick`] gets a word finding saying `says`.
    fn assert_word_finding(instruction: &str, object: &str, select: &str, says: &str) {
        let f = findings_for_pick(instruction, object, select);
        assert!(
            f.iter()
                .any(|x| x.kind == FindingKind::Word && x.to_model.contains(says)),
            "{instruction}: {f:?}"
        );
    }

    /// The findings on a plan of one move to `object` picked with `select`, for
    /// `instruction` as a possible answer to `earlier`.
    fn findings_after(
        earlier: &str,
        instruction: &str,
        object: &str,
        select: &str,
    ) -> Vec<Finding> {
        let m = map();
        let a = parse_answer(&format!(
            "objects: [({object}, None, None)]\nplan:\nmove_to_object(get_obj(\"{object}\", {select}));"
        ))
        .unwrap();
        check_answer_after(
            &m,
            instruction,
            Some(earlier),
            &a.tuples,
            &a.plan,
            m.start_pose,
            &[],
            &[],
            &[],
        )
    }

    #[test]
    fn the_words_of_an_earlier_instruction_count_as_said_never_as_asked() {
        // "sorry, the one by the tv" after "the black sofa by the window" got a question:
        // the black sofa is what the person said, so its colour is no made-up one...
        let pick = "#{colour: \"black\", near: get_obj(\"tv\")}";
        let unsaid = |f: &[Finding]| f.iter().any(|x| x.to_model.contains("did not say"));
        assert!(unsaid(&findings_for_pick(
            "sorry, the one by the tv",
            "sofa",
            pick
        )));
        let f = findings_after(
            "take me to the black sofa by the window",
            "sorry, the one by the tv",
            "sofa",
            pick,
        );
        assert!(!unsaid(&f), "{f:?}");
        // ...and so is a count ("the second chair", then "the black one").
        let pick = "#{ordinal: 2, colour: \"black\"}";
        let counted = |f: &[Finding]| f.iter().any(|x| x.to_model.contains("no such count"));
        assert!(counted(&findings_for_pick("the black one", "chair", pick)));
        let f = findings_after("go to the second chair", "the black one", "chair", pick);
        assert!(!counted(&f) && !unsaid(&f), "{f:?}");
        // But what the earlier words asked for is not asked now: "i meant the red one"
        // after "the black sofa" wants no black.
        let f = findings_after(
            "go to the black sofa",
            "oh sorry, i meant the red one",
            "sofa",
            "#{colour: \"red\"}",
        );
        assert!(f.iter().all(|x| !x.to_model.contains("black")), "{f:?}");
        assert!(f.is_empty(), "{f:?}");
    }

    #[test]
    fn a_room_left_out_is_named_with_the_forms_a_room_takes() {
        let f = findings_for_pick(
            "go to the red sofa and then the kitchen",
            "sofa",
            "#{colour: \"red\"}",
        );
        let room = f
            .iter()
            .find(|x| x.kind == FindingKind::Word && x.to_user.contains("kitchen"))
            .unwrap_or_else(|| panic!("{f:?}"));
        assert!(
            room.to_model.contains("move_to_object(\"kitchen\")")
                && room.to_model.contains("region: \"kitchen\"")
                && !room.to_model.contains("get_obj(\"kitchen\""),
            "{room:?}"
        );
        // An object left out is still to be picked with get_obj.
        assert_word_finding(
            "go to the red sofa and then the fridge",
            "sofa",
            "#{colour: \"red\"}",
            "get_obj(\"fridge\"",
        );
    }

    #[test]
    fn counting_from_the_end_of_far_to_near_or_of_a_size_order_is_found() {
        // Either is what a positive ordinal says the way it is said (the grammar offers
        // only that): "the bed that's farthest away" as the last far-to-near (the
        // nearest), "the biggest bed" as the last smallest-first.
        for (instruction, select, says) in [
            (
                "go to the bed that's farthest away",
                "#{ordinal: -1, order: \"far_to_near\"}",
                "write ordinal: 1 (nearest first) for that, or ordinal: -1 alone for the farthest",
            ),
            (
                "go to the biggest bed",
                "#{ordinal: -1, order: \"smallest_to_largest\"}",
                "write ordinal: 1 with order \"largest_to_smallest\" for that",
            ),
            (
                "go to the second smallest bed",
                "#{ordinal: -2, order: \"largest_to_smallest\"}",
                "write ordinal: 2 with order \"smallest_to_largest\" for that",
            ),
        ] {
            assert_word_finding(instruction, "bed", select, says);
        }
        // From the end of a direction, or of the default order, passes.
        let f = findings(
            "go to the penultimate bed from the west",
            "objects: [(bed, 2, None, west_to_east)]\nplan:\nmove_to_object(get_obj(\"bed\", #{ordinal: -2, order: \"west_to_east\"}));",
        );
        assert!(!f.iter().any(|x| x.to_model.contains("for that")), "{f:?}");
    }

    #[test]
    fn an_answer_that_says_everything_passes() {
        let f = findings(
            "go to the second black chair, then the red sofa",
            "objects: [(chair, 2, black), (sofa, None, red)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 2, colour: \"black\"}));\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));",
        );
        assert!(f.is_empty(), "{f:?}");
    }

    #[test]
    fn a_superlative_counted_from_the_wrong_end_is_found() {
        // Qwen 1.5B on people.nav: "the biggest bed" as the last largest-first (the
        // smallest), "the table furthest from you" as the last farthest-first (the
        // nearest). Both were silent wrong plans.
        for (instruction, select, says) in [
            (
                "go to the biggest bed",
                "#{ordinal: -1, order: \"largest_to_smallest\"}",
                "write ordinal: 1 with order \"largest_to_smallest\"",
            ),
            (
                "go to the table furthest from you",
                "#{ordinal: -1, order: \"far_to_near\"}",
                "is the nearest",
            ),
            // Held-out v2 ("the shelf furthest north" as the southernmost).
            (
                "go to the table furthest north",
                "#{ordinal: -1, order: \"north_to_south\"}",
                "write ordinal: 1 with order \"north_to_south\"",
            ),
            (
                "go to the table furthest west",
                "#{ordinal: 1, order: \"east_to_west\"}",
                "write ordinal: 1 with order \"west_to_east\"",
            ),
            (
                "go to the table furthest east",
                "#{ordinal: -1}",
                "no object in the plan is counted in the order \"east_to_west\"",
            ),
            (
                "go to the table furthest to the east",
                "#{ordinal: -1}",
                "no object in the plan is counted in the order \"east_to_west\"",
            ),
        ] {
            let object = if instruction.contains("bed") {
                "bed"
            } else {
                "table"
            };
            assert_word_finding(instruction, object, select, says);
        }
        // Either end, counted the right way, passes.
        for (instruction, select) in [
            (
                "go to the biggest bed",
                "#{ordinal: 1, order: \"largest_to_smallest\"}",
            ),
            (
                "go to the second biggest bed",
                "#{ordinal: 2, order: \"largest_to_smallest\"}",
            ),
            ("go to the bed furthest from you", "#{ordinal: -1}"),
            (
                "go to the bed furthest from you",
                "#{order: \"far_to_near\"}",
            ),
            (
                "go to the bed furthest north",
                "#{ordinal: 1, order: \"north_to_south\"}",
            ),
            (
                "go to the bed furthest north",
                "#{order: \"north_to_south\"}",
            ),
            (
                "go to the bed furthest north",
                "#{ordinal: -1, order: \"south_to_north\"}",
            ),
            // A side a word or two later ([`side_after`]; held-out v8, dev, hr11).
            (
                "go to the bed furthest to the left",
                "#{ordinal: 1, order: \"left_to_right\"}",
            ),
            (
                "go to the bed furthest to the east",
                "#{order: \"east_to_west\"}",
            ),
            (
                "go to the bed furthest from you on the left",
                "#{ordinal: -1}",
            ),
            // Three words on (held-out v16, dev, va02).
            (
                "go to the bed furthest along to the east",
                "#{ordinal: 1, order: \"east_to_west\"}",
            ),
            // The one before the last is the second to last (held-out v16, dev, vb08).
            (
                "count the beds west to east and go to the one right before the last",
                "#{ordinal: -2, order: \"west_to_east\"}",
            ),
        ] {
            let f = findings_for_pick(instruction, "bed", select);
            assert!(
                f.iter().all(|x| x.kind != FindingKind::Word),
                "{instruction} {select}: {f:?}"
            );
        }
    }

    #[test]
    fn a_directional_superlative_is_judged_on_its_object() {
        // Held-out v2: "the desk furthest west" as the last west-first (the easternmost)
        // passed, because another target (a shelf) had the order west_to_east.
        let wrong = "objects: [(desk, 1, None, west_to_east), (shelf, None, white)]\nplan:\nmove_to_object(get_obj(\"desk\", #{ordinal: -1, order: \"west_to_east\"}));\nmove_south(get_obj(\"shelf\", #{colour: \"white\", order: \"west_to_east\"}));";
        let f = findings(
            "go to the desk furthest west, then south of the white shelf",
            wrong,
        );
        assert!(
            f.iter().any(|x| x.kind == FindingKind::Word
                && x.to_model
                    .contains("write ordinal: 1 with order \"west_to_east\"")),
            "{f:?}"
        );
        let right = wrong.replace("ordinal: -1", "ordinal: 1");
        let f = findings(
            "go to the desk furthest west, then south of the white shelf",
            &right,
        );
        assert!(f.iter().all(|x| x.kind != FindingKind::Word), "{f:?}");
    }

    #[test]
    fn an_ordinal_the_person_did_not_say_is_found() {
        // Seen on people.nav: "the small table next to the blue bed" as the second table
        // near the bed; "the yellow table that's furthest from you" as the third.
        let counted = |instruction: &str, select: &str| {
            let f = findings(
                instruction,
                &format!("objects: [(table, None, None)]\nplan:\nmove_to_object(get_obj(\"table\", {select}));"),
            );
            let found = f.iter().any(|x| {
                x.kind == FindingKind::Word
                    && x.to_model.contains("said no such count")
                    && x.to_user.starts_with("which table do you mean? there are")
            });
            (found, f)
        };
        for (instruction, select) in [
            (
                "go to the small table next to the bed",
                "#{ordinal: 2, near: get_obj(\"bed\")}",
            ),
            (
                "go to the table that's furthest from you",
                "#{ordinal: 3, order: \"far_to_near\"}",
            ),
            ("go to the third table", "#{ordinal: 2}"),
            ("go to the table by the door", "#{ordinal: -2}"),
        ] {
            let (found, f) = counted(instruction, select);
            assert!(found, "{instruction}: {f:?}");
        }
        // Counts said as words, numbers, typos or "penultimate" pass, and so do the
        // first and the last, however said.
        for (instruction, select) in [
            ("go to the second table", "#{ordinal: 2}"),
            ("go to table number 3", "#{ordinal: 3}"),
            ("go to table three", "#{ordinal: 3}"),
            ("go to the 3rd table", "#{ordinal: 3}"),
            ("go to the thrid table", "#{ordinal: 3}"),
            ("go to the penultimate table", "#{ordinal: -2}"),
            ("go to the second to last table", "#{ordinal: -2}"),
            ("go to the table furthest away", "#{ordinal: -1}"),
            ("go to the closest table", "#{ordinal: 1}"),
            // The second from an end, where a side or the far end is said
            // ([`counts_offered`]): "one shy of the end" names no number.
            (
                "counting from the west, the table one shy of the end",
                "#{ordinal: 2, order: \"east_to_west\"}",
            ),
            ("the next-to-farthest table", "#{ordinal: -2}"),
        ] {
            let (found, f) = counted(instruction, select);
            assert!(!found, "{instruction} {select}: {f:?}");
        }
        // In a conversation too: a visited instance's id written as the count ("now the
        // other red chair" after red chair 9, seen on the chat suite) is found; "the
        // other one" has its own key, and a said count stays said.
        let m = map();
        for (instruction, select, found) in [
            ("now the other table", "#{ordinal: 8}", true),
            (
                "now the other table",
                "#{other_than: get_instance(8)}",
                false,
            ),
            ("now the second table", "#{ordinal: 2}", false),
        ] {
            let a = parse_answer(&format!(
                "objects: [(table, None, None)]\nplan:\nmove_to_object(get_obj(\"table\", {select}));"
            ))
            .unwrap();
            let f = check_answer(&m, instruction, &a.tuples, &a.plan, m.start_pose, &[], &[8]);
            assert_eq!(
                f.iter().any(|x| x.to_model.contains("no such count")),
                found,
                "{instruction} {select}: {f:?}"
            );
        }
    }

    #[test]
    fn a_region_the_person_did_not_name_is_found() {
        // Qwen 1.5B on held-out v2: "the sink in the bathroom, then uh the lamp" gave the
        // lamp the bathroom too; "the stool furthest east" was looked for in a room
        // nobody named.
        let answer = "objects: [(sink, None, None), (lamp, None, None)]\nplan:\nmove_to_object(get_obj(\"sink\", #{region: \"bathroom\"}));\nmove_to_object(get_obj(\"lamp\", #{region: \"office\"}));";
        let f = findings("the sink in the bathroom, then uh the lamp", answer);
        let regions: Vec<_> = f
            .iter()
            .filter(|x| x.to_model.contains("did not name the"))
            .collect();
        assert_eq!(regions.len(), 1, "{f:?}");
        assert!(regions[0].to_model.contains("lamp in the office"), "{f:?}");
        // Named in any form: a synonym, a typo, the plural.
        for instruction in [
            "the sink in the restroom, then the lamp in the ofice",
            "the bathroom sink, then the lamp in the offices",
        ] {
            let f = findings(instruction, answer);
            assert!(
                f.iter().all(|x| !x.to_model.contains("did not name the")),
                "{instruction}: {f:?}"
            );
        }
        // The lounge is the living room.
        let said = region_said("the chair in the lounge", &[]);
        assert!(said("living room") && !said("dining room") && !said("kitchen"));
        let said = region_said("the plant in the dining room, the cafetria", &[]);
        assert!(said("dining room") && !said("living room") && said("cafeteria"));
        // A word of an object's name is that name, not a typo of a room's (held-out v7,
        // dev, ho11: "the display case" and the cafe).
        let exact = ["display".to_string(), "case".to_string()];
        assert!(region_said("the white display case, then the counter", &[])("cafe"));
        assert!(!region_said(
            "the white display case, then the counter",
            &exact
        )("cafe"));
        assert!(region_said("the display case in the cafee", &exact)("cafe"));
    }

    /// Asserts that `order` on "chair number 3" is found, with a message holding `says`,
    /// where the words are `unsaid`, and not where any of `said` are.
    fn assert_unsaid_order_found(order: &str, unsaid: &str, says: &str, said: &[&str]) {
        let answer = format!("objects: [(chair, 3, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{{ordinal: 3, order: \"{order}\"}}));");
        let f = findings(unsaid, &answer);
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(f[0].to_model.contains(says), "{f:?}");
        for instruction in said {
            let f = findings(instruction, &answer);
            assert!(
                f.iter().all(|x| !x.to_model.contains(says)),
                "{instruction}: {f:?}"
            );
        }
    }

    #[test]
    fn an_order_by_size_the_person_did_not_say_is_found() {
        // Qwen 1.5B on people.nav: "chair number 3" counted largest first.
        assert_unsaid_order_found(
            "largest_to_smallest",
            "then chair number 3",
            "nothing of size",
            &[
                "the third biggest chair",
                "the 3rd chair by size",
                "the third large chair",
            ],
        );
    }

    #[test]
    fn a_colour_said_before_its_noun_is_not_an_excluded_colour() {
        // Qwen 1.5B on held-out v2's hf11 (dev): "the yellow table furthest from you" as
        // the farthest table that is not yellow, which no check found.
        assert_word_finding(
            "go to the red sofa furthest from you",
            "sofa",
            "#{ordinal: -1, not_colour: \"red\"}",
            "the person said \"red sofa\", but no sofa in the plan has colour \"red\"",
        );
        for said in [
            "go to the sofa, not the red sofa",
            "go to a sofa other than the red sofa",
            "go to the sofa that isn't red",
            // Held-out v17 (dev) wb09's form.
            "go to a non-red sofa",
        ] {
            assert_no_finding(said, "sofa", "#{not_colour: \"red\"}", "has colour \"red\"");
        }
        let m = map();
        let a = parse_answer("objects: [(sofa, None, red)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));").unwrap();
        let f = check_answer(
            &m,
            "go to a non-red sofa",
            &a.tuples,
            &a.plan,
            m.start_pose,
            &[],
            &[],
        );
        assert!(
            f.iter().any(|x| x.to_model.contains("only to exclude it")),
            "a non-red sofa written red: {f:?}"
        );
        // Said kept elsewhere: the red sofa may be a stop of its own.
        let f = check_answer(
            &m,
            "go to the red sofa, then a chair that isn't red",
            &a.tuples,
            &a.plan,
            m.start_pose,
            &[],
            &[],
        );
        assert!(
            f.iter().all(|x| !x.to_model.contains("only to exclude it")),
            "{f:?}"
        );
    }

    #[test]
    fn a_far_end_the_person_did_not_say_is_found() {
        // Qwen 1.5B on held-out v2's hd07 (dev), re-asked: "third stool" as the third
        // farthest.
        assert_unsaid_order_found(
            "far_to_near",
            "third chair please",
            "nothing of the far end",
            &[
                "the third chair furthest from you",
                "the third farthest chair",
                "the 3rd most distant chair",
                "the chair third from the far end",
                "the third to last chair",
            ],
        );
    }

    #[test]
    fn second_to_last_counts_from_the_end() {
        // Qwen 1.5B on held-out v2 (dev), re-asked: "the second to last bed" as the
        // second nearest.
        let said = "go to the second to last bed";
        assert_word_finding(
            said,
            "bed",
            "#{ordinal: 2}",
            "\"the second to last\", but no bed in the plan has ordinal -2 (or 2 counted from the other end)",
        );
        for ok in ["#{ordinal: -2}", "#{ordinal: 2, order: \"far_to_near\"}"] {
            let f = findings_for_pick(said, "bed", ok);
            assert!(f.is_empty(), "{ok}: {f:?}");
        }
        let f = findings_for_pick(
            "go to the third to last bed from the west",
            "bed",
            "#{ordinal: 3, order: \"east_to_west\"}",
        );
        assert!(f.is_empty(), "{f:?}");
        // "the second" alone still counts from the start.
        assert!(findings_for_pick("go to the second bed", "bed", "#{ordinal: 2}").is_empty());
    }

    #[test]
    fn a_superlative_no_reading_reads_leaves_sizes_and_the_far_end_open() {
        for s in [
            "the remotest vinyl crate",
            "the parcel locker that's the longest way from you",
            "the most compact picnic table",
            "the fattest picnic table, then the teeniest one",
            "the sleeper stack with the biggest footprint and then the one with the least",
            "the sleeper stack covering the least floor space",
        ] {
            assert!(superlative_unread(s), "{s}");
            assert!(size_said(s, Some(&[])), "{s}");
            assert!(far_end_said(s), "{s}");
        }
        // Read superlatives, and words that are none.
        for s in [
            "the nearest chair, then the closest table",
            "the westernmost shelf and the most northern lamp",
            "the biggest rug, then the smallest table",
            "the furthest bin, then the most distant chair",
            "the chest by the west wall",
            "at least go to the sofa",
            "the second table",
        ] {
            assert!(!superlative_unread(s), "{s}");
        }
        assert!(!far_end_said(
            "the nearest chair, then the westernmost shelf"
        ));
        assert!(!size_said("the closest table", Some(&[])));
    }

    #[test]
    fn a_plain_size_word_speaks_of_size_only_before_a_name() {
        let names: Vec<String> = ["table", "booth", "seat", "claw", "machine"]
            .map(String::from)
            .to_vec();
        let said = |s: &str| size_said(s, Some(&names));
        for s in [
            "the small table",
            "the big red booth seat",
            "the tables, the small one",
            "go to the smallest",
            "the second biggest claw machine",
            "the larger table",
            "the tiniest seat",
            "sort the tables by size",
            "the little tables",
        ] {
            assert!(said(s), "{s}");
            assert!(size_said(s, None), "{s}");
        }
        // Held-out v12 (dev) ma02.
        for s in [
            "Small favour: shoot over to the booth seat furthest east, then claw machine number 2",
            "go a little further, then the table",
        ] {
            assert!(!said(s), "{s}");
            assert!(size_said(s, None), "{s}");
        }
        // Held-out v17 (dev) wb02: a sentence ends before the name; a comma does not.
        assert!(!said(
            "Robot, little list: the booth seat right at the west end"
        ));
        assert!(said("the big, red table"));
        let a = parse_answer("objects: [(chair, 2, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 2, order: \"smallest_to_largest\"}));").unwrap();
        let plan = &a.plan;
        let names = object_name_words(&map());
        assert_eq!(
            unsaid_sizes(
                "small favour: could you go to chair number 2",
                Some(&names),
                plan
            )
            .len(),
            1
        );
        assert!(unsaid_sizes("the small chair number 2", Some(&names), plan).is_empty());
    }

    #[test]
    fn next_to_last_and_last_but_one_count_from_the_end() {
        // Held-out v12 (dev since its third run) ma09 and mc09: "the last-but-one ball
        // return counting from the west" was read as "one ... from the west" and "the
        // next-to-last staff locker counting from the west" as "last ... from the west":
        // the first from each end passed.
        for said in ["go to the next-to-last bed", "go to the last but one bed"] {
            let f = findings_for_pick(said, "bed", "#{ordinal: -1}");
            assert!(
                f.iter().any(|x| x.to_model.contains("has ordinal -2")),
                "{said}: {f:?}"
            );
            for ok in ["#{ordinal: -2}", "#{ordinal: 2, order: \"far_to_near\"}"] {
                let f = findings_for_pick(said, "bed", ok);
                assert!(f.is_empty(), "{said}, {ok}: {f:?}");
            }
        }
        for said in [
            "go to the next-to-last bed counting from the west",
            "go to the last-but-one bed counting from the west",
            "counting from the west, go to the last but one bed",
        ] {
            for wrong in [
                "#{ordinal: 1, order: \"west_to_east\"}",
                "#{ordinal: 1, order: \"east_to_west\"}",
                "#{ordinal: -1, order: \"west_to_east\"}",
            ] {
                let f = findings_for_pick(said, "bed", wrong);
                assert!(!f.is_empty(), "{said}, {wrong}");
            }
            for ok in [
                "#{ordinal: 2, order: \"east_to_west\"}",
                "#{ordinal: -2, order: \"west_to_east\"}",
            ] {
                let f = findings_for_pick(said, "bed", ok);
                assert!(f.is_empty(), "{said}, {ok}: {f:?}");
            }
        }
        assert!(
            counts_said("the last-but-one bed, then the next to last chair")
                .iter()
                .all(|&k| k == 2)
        );
    }

    #[test]
    fn a_count_is_said_of_the_name_past_one_more_word_or_a_typo() {
        // Held-out v3 (dev) hg14: "the second nearest bycicle" read no name after the
        // count, so another object's ordinal 2 let a plain pick of the bicycle pass.
        let answer = |chair: &str| {
            format!(
                "objects: [(plant, 2, None), (chair, 2, None)]\nplan:\nmove_to_object(get_obj(\"plant\", #{{ordinal: 2}}));\nmove_to_object(get_obj(\"chair\"{chair}));"
            )
        };
        for (said, wrong, right) in [
            (
                "go to the second plant, then the second nearest chair",
                "",
                ", #{ordinal: 2}",
            ),
            (
                "go to the second plant, then the second nearest chiar",
                "",
                ", #{ordinal: 2}",
            ),
            (
                "go to the second plant, then the second closest black chiar",
                ", #{colour: \"black\"}",
                ", #{ordinal: 2, colour: \"black\"}",
            ),
        ] {
            let f = findings(said, &answer(wrong));
            assert!(
                f.iter().any(|x| x.kind == FindingKind::Word
                    && x.to_model.contains("the count belongs to the chair")),
                "{said}: {f:?}"
            );
            let ok = findings(said, &answer(right));
            assert!(ok.is_empty(), "{said}: {ok:?}");
        }
        // A word that is no typo of a name leaves the count on any target, as before.
        let f = findings(
            "go to the second plant, then the second nearest thing",
            &answer(""),
        );
        assert!(
            !f.iter().any(|x| x.to_model.contains("the count belongs")),
            "{f:?}"
        );
        let m = map();
        let w = words("the second nearest bycicle");
        assert_eq!(typed_label_at(&m, &w, 3), None, "flat-a has no bicycle");
        let w = words("the second chiar and the tabel");
        assert_eq!(
            typed_label_at(&m, &w, 2),
            Some(("chiar".into(), "chair".into()))
        );
        assert_eq!(
            typed_label_at(&m, &w, 5),
            Some(("tabel".into(), "table".into()))
        );
        assert_eq!(typed_label_at(&m, &w, 1), None, "second");
    }

    #[test]
    fn a_count_after_number_is_said_of_the_name_before_it() {
        // Held-out v4 (dev) hk05: "chair number 3, then the plant" was read as the
        // plant's count, and a right plan became a question.
        let answer = |chair: &str, plant: &str| {
            format!(
                "objects: [(chair, 2, None), (plant, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\"{chair}));\nmove_to_object(get_obj(\"plant\"{plant}));"
            )
        };
        let said = "go to chair number 2, then the plant";
        let ok = findings(said, &answer(", #{ordinal: 2}", ""));
        assert!(ok.is_empty(), "{ok:?}");
        let f = findings(said, &answer("", ", #{ordinal: 2}"));
        assert!(
            f.iter().any(|x| x.kind == FindingKind::Word
                && x.to_model.contains(
                    "\"chair number 2\", but no chair in the plan has ordinal 2: the count belongs to the chair"
                )),
            "{f:?}"
        );
        // With no name before "number", the name after it: "number 2 chair".
        let f = findings(
            "go to number 2 chair, then the plant",
            &answer("", ", #{ordinal: 2}"),
        );
        assert!(
            f.iter()
                .any(|x| x.to_model.contains("the count belongs to the chair")),
            "{f:?}"
        );
    }

    #[test]
    fn a_stop_between_said_is_a_stop_between() {
        let said = "go to the chair, then stop between the table and the white sofa";
        let near = "objects: [(chair, None, None), (table, None, None), (sofa, None, white)]\nplan:\nmove_to_object(get_obj(\"chair\"));\nmove_to_object(get_obj(\"table\", #{near: get_obj(\"sofa\", #{colour: \"white\"})}));";
        let f = findings(said, near);
        assert!(
            f.iter().any(|x| x.kind == FindingKind::Word
                && x.to_model.contains("the plan stops between nothing")),
            "{f:?}"
        );
        let between = "objects: [(chair, None, None), (table, None, None), (sofa, None, white)]\nplan:\nmove_to_object(get_obj(\"chair\"));\nmove_in_between(get_obj(\"table\"), get_obj(\"sofa\", #{colour: \"white\"}));";
        let f = findings(said, between);
        assert!(
            f.iter().all(|x| !x.to_model.contains("between nothing")),
            "{f:?}"
        );
        assert!(!between_said("go to the chair, then the table"));
        assert!(between_said("stop in between the two sofas"));
    }

    #[test]
    fn a_colour_said_of_another_object_is_no_request_for_this_one() {
        let not_on_map = |said: &str, line: &str| {
            let answer = format!("objects: [{line}]\nplan:\nmove_to_object(get_obj(\"plant\", #{{near: get_obj(\"sofa\", #{{colour: \"black\"}})}}));");
            findings(said, &answer)
                .into_iter()
                .any(|x| x.kind == FindingKind::NotOnMap)
        };
        // Held-out v7 (dev) hq08's form: the colour belongs to the anchor.
        assert!(!not_on_map(
            "go to the plant next to the black sofa",
            "(plant, None, black), (sofa, None, black)"
        ));
        // Said of the object itself: the person may be wrong about the map; ask.
        assert!(not_on_map(
            "go to the black plant next to the black sofa",
            "(plant, None, black), (sofa, None, black)"
        ));
        assert!(not_on_map(
            "go to the plant, the black one",
            "(plant, None, black)"
        ));
        // Said after a word that excludes, a colour is no colour of anything (held-out
        // v10, dev, ka10's form).
        assert!(!not_on_map(
            "a plant that isn't black, then the one next to the black sofa",
            "(plant, None, black), (sofa, None, black)"
        ));
        assert!(!not_on_map(
            "go to the plant that isn't black",
            "(plant, None, black)"
        ));
    }

    #[test]
    fn a_colour_is_excluded_only_where_the_words_exclude_one() {
        // Held-out v7 (dev) ho11: "the white display case ..., then the counter" as a
        // counter `#{not_colour: "white"}`: white is said, of another object.
        let says = "but the person excluded nothing";
        assert_word_finding(
            "go to the white desk, then the table",
            "table",
            "#{not_colour: \"white\"}",
            says,
        );
        for said in [
            "go to the table that isn't white",
            "go to the table that isnt white",
            "a table other than the white one",
        ] {
            assert_no_finding(said, "table", "#{not_colour: \"white\"}", says);
            assert_no_finding(said, "table", "#{not_colour: \"white\"}", "did not exclude");
        }
        // Said, but not after the excluding word (held-out v8, dev, ht02).
        assert_word_finding(
            "the white desk, then the table that isn't black",
            "table",
            "#{not_colour: \"white\"}",
            "but the person did not exclude white",
        );
        assert_no_finding(
            "the white desk, then the table that isn't black",
            "table",
            "#{not_colour: \"black\"}",
            "did not exclude",
        );
    }

    #[test]
    fn clauses_end_at_punctuation_arrows_and_joining_words() {
        let c =
            clauses("the sofa, then the table -> the chair next to the tv and the bed. Next: go");
        let c: Vec<String> = c.iter().map(|w| w.join(" ")).collect();
        assert_eq!(
            c,
            [
                "the sofa",
                "the table",
                "the chair next to the tv",
                "the bed",
                "go"
            ]
        );
    }

    #[test]
    fn a_region_is_said_of_the_objects_of_its_clause() {
        let m = map();
        let of = |s: &str| regions_said_of(&m, s, m.start_pose);
        let r = |l: &str, rs: &[&str]| {
            (
                l.to_string(),
                rs.iter().map(|x| (*x).to_string()).collect::<Vec<String>>(),
            )
        };
        // Held-out v10 (dev) ka05's form on flat-a: the room of the last clause, which
        // names no object, is the table's before it, not the chair's.
        assert_eq!(
            of("the chair closest to the red sofa. Then the third table, and then into the kitchen"),
            [r("chair", &[]), r("sofa", &[]), r("table", &["kitchen"])]
        );
        // In the clause naming it; a clause naming no object goes with those around it.
        assert_eq!(
            of("the chair in the kitchen, then the sofa"),
            [r("chair", &["kitchen"]), r("sofa", &[])]
        );
        assert_eq!(
            of("in the bedroom, the second chair, then the tv"),
            [r("chair", &["bedroom"]), r("tv", &[])]
        );
        // A room's synonym and a typo, and an object's synonym.
        assert_eq!(
            of("the couch in the lounge, then the table in the kitchn"),
            [r("sofa", &["living room"]), r("table", &["kitchen"])]
        );
        // No room said: every label with none.
        assert_eq!(
            of("the sofa, then the chair"),
            [r("sofa", &[]), r("chair", &[])]
        );
    }

    #[test]
    fn a_pick_in_a_room_said_of_another_object_is_found() {
        let findings = |instruction: &str, answer: &str| {
            let m = map();
            let a = parse_answer(answer).unwrap();
            check_regions_of_others(&m, instruction, &a.plan, m.start_pose)
        };
        let said =
            "the chair closest to the red sofa. Then the third table, and then into the kitchen";
        let answer = |chair: &str| {
            format!("objects: [(chair, None, None), (sofa, None, red), (table, 3, None), (kitchen, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{{{chair}near: get_obj(\"sofa\", #{{colour: \"red\"}})}}));\nmove_to_object(get_obj(\"table\", #{{ordinal: 3}}));\nmove_to_object(\"kitchen\");")
        };
        let f = findings(said, &answer("region: \"kitchen\", "));
        assert!(
            f.iter()
                .any(|x| x.to_model.contains("did not put the chair in the kitchen")),
            "{f:?}"
        );
        let f = findings(said, &answer(""));
        assert!(
            f.iter().all(|x| !x.to_model.contains("did not put")),
            "{f:?}"
        );
        // Said of the table, the table may be picked there.
        let table = "objects: [(table, 3, None), (kitchen, None, None)]\nplan:\nmove_to_object(get_obj(\"table\", #{ordinal: 3, region: \"kitchen\"}));";
        let f = findings("the third table, and then into the kitchen", table);
        assert!(
            f.iter().all(|x| !x.to_model.contains("did not put")),
            "{f:?}"
        );
    }

    #[test]
    fn a_direction_is_said_of_the_objects_of_its_clause() {
        let m = map();
        let of = |s: &str| said_of_map(&m, s, m.start_pose, SaidOf::Direction);
        // Held-out v8 (dev) hr04 and ht04, on flat-a's names.
        assert_eq!(
            of("the penultimate chair first. Next the 2nd table counting from the west"),
            Some(vec!["table".to_string()])
        );
        assert_eq!(
            of("the second to last sofa, then the second chair counting from the east, then the bed"),
            Some(vec!["chair".to_string()])
        );
        // A clause naming no object: the objects of the clauses around it.
        assert_eq!(
            of("the chairs, the one furthest west"),
            Some(vec!["chair".to_string()])
        );
        assert_eq!(
            of("the sofa, then counting from the east, the second chair"),
            Some(vec!["chair".to_string(), "sofa".to_string()])
        );
        // A synonym, a typo and a two-word name count as their labels.
        assert_eq!(
            of("the couch furthest north, then the tabel on the left"),
            Some(vec!["sofa".to_string(), "table".to_string()])
        );
        // No direction said: none; a direction of no object anywhere: no narrowing.
        assert_eq!(of("the third chair, then the sofa"), None);
        assert_eq!(of("turn left"), None);
    }

    #[test]
    fn a_count_is_said_of_the_objects_of_its_clause() {
        let m = map();
        let of = |s: &str| said_of_map(&m, s, m.start_pose, SaidOf::Count);
        // Held-out v8 (dev) ht12, on flat-a's names.
        assert_eq!(
            of("fridge, red sofa, 2nd chair from the west, kitchen"),
            Some(vec!["chair".to_string()])
        );
        assert_eq!(
            of("the penultimate sofa, then table number 3"),
            Some(vec!["sofa".to_string(), "table".to_string()])
        );
        // A count cut off from its name by a full stop is the name's before it.
        assert_eq!(
            of("the sofa nr. 2, then a chair that isn't red"),
            Some(vec!["sofa".to_string()])
        );
        // "First" and "last" place no count; nor does no count at all.
        assert_eq!(of("the first chair, then the last sofa"), None);
        let says = "but the person said a count only of the chair";
        let f = findings(
            "the red sofa, then the 2nd chair from the west",
            "objects: [(sofa, None, red), (chair, 2, None)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{ordinal: 2, colour: \"red\"}));\nmove_to_object(get_obj(\"chair\", #{ordinal: 2, order: \"west_to_east\"}));",
        );
        assert!(
            f.iter().any(|x| x.to_model.contains(says)
                && x.to_model.contains("picks the sofa with ordinal 2")),
            "{f:?}"
        );
        assert!(
            f.iter()
                .all(|x| !x.to_model.contains("picks the chair with")),
            "{f:?}"
        );
    }

    #[test]
    fn a_count_from_the_far_end_said_of_another_object_is_a_finding() {
        let m = map();
        let of = |s: &str| said_of_map(&m, s, m.start_pose, SaidOf::FarEnd);
        // Held-out v9 (dev) hv04's shape, on flat-a's names.
        assert_eq!(
            of("the second-to-last chair, then the red sofa in the kitchen"),
            Some(vec!["chair".to_string()])
        );
        assert_eq!(of("the red sofa, then the third chair"), None);
        let says = "but the person spoke of the far end only for the chair";
        let f = findings(
            "the second-to-last chair, then the red sofa",
            "objects: [(chair, 2, None, far_to_near), (sofa, None, red)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 2, order: \"far_to_near\"}));\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\", order: \"far_to_near\"}));",
        );
        assert!(
            f.iter().any(|x| x.to_model.contains(says)
                && x.to_model
                    .contains("counts the sofa in order \"far_to_near\"")),
            "{f:?}"
        );
        assert!(
            f.iter().all(|x| !x.to_model.contains("counts the chair")),
            "{f:?}"
        );
        // -1 of the default order is the farthest too (held-out v10's ka03 shape).
        let f = findings(
            "the chair that's furthest from you, then the sofa, then the tv",
            "objects: [(chair, last, None), (sofa, last, None), (tv, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: -1}));\nmove_to_object(get_obj(\"sofa\", #{ordinal: -1}));\nmove_to_object(get_obj(\"tv\"));",
        );
        let sofa = f
            .iter()
            .find(|x| x.to_model.contains("picks the sofa with ordinal -1, counted from the far end, but the person spoke of the far end only for the chair"))
            .unwrap_or_else(|| panic!("{f:?}"));
        assert_eq!(sofa.about, Some(About::Step(1)), "the sofa's step");
        assert!(
            f.iter().all(|x| !x.to_model.contains("picks the chair")),
            "{f:?}"
        );
    }

    #[test]
    fn a_colour_the_plan_picks_where_it_makes_no_stop_is_carried() {
        // Held-out v16 (dev) va05's shape: the anchor's colour left out, where the
        // anchor the plan picks is of that colour anyway.
        let m = map();
        let colour_findings = |instruction: &str, answer: &str, picked: &[u32]| {
            let a = parse_answer(answer).unwrap();
            check_answer_after(
                &m,
                instruction,
                None,
                &a.tuples,
                &a.plan,
                m.start_pose,
                &[],
                picked,
                &[],
            )
            .into_iter()
            .filter(|x| x.to_model.contains("in the plan has colour"))
            .collect::<Vec<_>>()
        };
        let near = "objects: [(chair, None, None), (sofa, None, red)]\nplan:\nmove_to_object(get_obj(\"chair\", #{near: get_obj(\"sofa\")}));";
        let said = "go to the chair next to the red sofa";
        // Sofa 1 is the red one, 2 the black one; chair 7 is grey.
        assert!(colour_findings(said, near, &[1, 7]).is_empty());
        let f = colour_findings(said, near, &[2, 7]);
        assert!(
            f.iter().any(|x| x.to_model.contains("\"red sofa\"")),
            "{f:?}"
        );
        // A red object of another name picked is not the red chair said.
        let f = colour_findings("go to the red chair next to the sofa", near, &[1, 7]);
        assert!(
            f.iter().any(|x| x.to_model.contains("\"red chair\"")),
            "{f:?}"
        );
    }

    #[test]
    fn the_far_end_is_looked_for_on_the_object_it_is_said_of() {
        // Held-out v16 (dev) vb04's shape: the count from the far end written nearest
        // first, and another object counted far to near.
        let plan = |chair: &str| {
            format!("objects: [(chair, 2, None), (sofa, 1, None, far_to_near)]\nplan:\nmove_to_object(get_obj(\"chair\", {chair}));\nmove_to_object(get_obj(\"sofa\", #{{ordinal: 1, order: \"far_to_near\"}}));")
        };
        let said = "go to the chair that's second from farthest, then the sofa furthest from you";
        let f = findings(said, &plan("#{ordinal: 2}"));
        let x = f
            .iter()
            .find(|x| x.to_model.contains("the person said \"second from farthest\", but no object in the plan is counted so: that is ordinal: 2 with order \"far_to_near\""))
            .unwrap_or_else(|| panic!("{f:?}"));
        assert_eq!(x.about, Some(About::Label("chair".to_string())));
        assert_eq!(x.to_user, "which one is the second from farthest?");
        for right in [
            "#{ordinal: 2, order: \"far_to_near\"}",
            "#{ordinal: -2}",
            "#{ordinal: -2, order: \"near_to_far\"}",
        ] {
            let f = findings(said, &plan(right));
            assert!(
                f.iter().all(|x| !x.to_model.contains("farthest")),
                "{right}: {f:?}"
            );
        }
        // "from the farthest" says the same; the farthest alone is looked for on the
        // chair too, whichever side of it the chair is named.
        let f = findings(
            "the second from the farthest chair, then the sofa furthest from you",
            &plan("#{ordinal: 2}"),
        );
        assert!(
            f.iter()
                .any(|x| x.to_model.contains("\"second from the farthest\"")),
            "{f:?}"
        );
        for said in [
            "the farthest chair, then the sofa furthest from you",
            "the chair farthest from you, then the sofa furthest from you",
        ] {
            let f = findings(said, &plan("#{ordinal: 1}"));
            let x = f
                .iter()
                .find(|x| {
                    x.to_model
                        .contains("no object in the plan is counted from that end")
                        || x.to_model
                            .contains("ordinal -1 in order \"far_to_near\" is the nearest")
                })
                .unwrap_or_else(|| panic!("{said}: {f:?}"));
            assert_eq!(x.about, Some(About::Label("chair".to_string())), "{said}");
            let f = findings(said, &plan("#{ordinal: -1}"));
            assert!(
                f.iter().all(|x| !x.to_model.contains("farthest")),
                "{said}: {f:?}"
            );
        }
    }

    #[test]
    fn a_count_in_a_direction_said_of_another_object_is_a_finding() {
        let says = "but the person named a direction only for the table";
        let instruction = "the penultimate chair first, then the 2nd table counting from the west";
        let f = findings(
            instruction,
            "objects: [(chair, None, None), (table, 2, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 2, order: \"west_to_east\"}));\nmove_to_object(get_obj(\"table\", #{ordinal: 2, order: \"west_to_east\"}));",
        );
        assert!(
            f.iter().any(|x| x.to_model.contains(says)
                && x.to_model
                    .contains("counts the chair in order \"west_to_east\"")),
            "{f:?}"
        );
        assert!(
            f.iter().all(|x| !x.to_model.contains("counts the table")),
            "{f:?}"
        );
        // Said of the chair: no finding.
        assert_no_finding(
            "go to the second chair from the west, then the sofa",
            "chair",
            "#{ordinal: 2, order: \"west_to_east\"}",
            "named a direction only",
        );
    }

    #[test]
    fn an_anchor_is_an_object_the_person_named() {
        let pick = |anchor: &str| {
            format!("objects: [(chair, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{{near: get_obj(\"{anchor}\")}}));")
        };
        // Held-out v7 (dev) hq13: "the cabinet nearest to you" near a workbench.
        let f = findings("go to the chair nearest to you", &pick("sofa"));
        assert!(
            f.iter().any(|x| x.kind == FindingKind::Word
                && x.to_model
                    .contains("picks the chair near a sofa, but the person named no sofa")),
            "{f:?}"
        );
        // Named, by a synonym, or with a typo: no finding.
        for said in [
            "go to the chair nearest to the sofa",
            "go to the chair by the couch",
            "go to the chair closest to the sofaa",
        ] {
            let f = findings(said, &pick("sofa"));
            assert!(
                f.iter().all(|x| !x.to_model.contains("named no sofa")),
                "{said}: {f:?}"
            );
        }
    }

    #[test]
    fn a_side_stop_said_of_the_first_name_is_found_only_there() {
        let m = map();
        let first = |s: &str| side_said_first(&m, s, m.start_pose);
        let of = |side: Side, label: &str| Some((side, label.to_string()));
        assert_eq!(
            first("Stop to the left of the black sofa, then the tv"),
            of(Side::Left, "sofa")
        );
        assert_eq!(
            first("Position yourself on the north side of the white bed. Then the fridge."),
            of(Side::North, "bed")
        );
        // The room the robot is in, said first, says where it starts.
        assert_eq!(
            first("From the living room: park on the south side of the bed, then the tv"),
            of(Side::South, "bed")
        );
        // The first name is another object, or a room to go into first.
        assert_eq!(
            first("go to the tv, then stop to the left of the sofa"),
            None
        );
        assert_eq!(
            first("go into the kitchen and stop on the north side of the fridge"),
            None
        );
        // The object is named again, or no side is said of it.
        assert_eq!(
            first("stop to the left of the sofa, then the tv, then the sofa again"),
            None
        );
        assert_eq!(first("the sofa, then to the left of the tv"), None);
        assert_eq!(first("go to the chair to the left of the table"), None);
    }

    #[test]
    fn a_side_stop_said_is_a_move_to_that_side_of_that_object() {
        let m = map();
        let said = |s: &str| side_moves_said(&m, &words(s), m.start_pose);
        let one = |side: Side, word: &str, of: Option<&str>| SideSaid {
            side,
            word: word.to_string(),
            of: of.map(str::to_string),
        };
        assert_eq!(
            said("stop to the left of the black sofa, then the tv"),
            vec![one(Side::Left, "left", Some("sofa"))]
        );
        assert_eq!(
            said("park on the south side of the bed and wait on the right-hand side of the tv"),
            vec![
                one(Side::South, "south", Some("bed")),
                one(Side::Right, "right", Some("tv"))
            ]
        );
        assert_eq!(
            said("go to the fridge, then just north of it"),
            vec![one(Side::North, "north", None)]
        );
        // Not a stop at a side: a turn, a count, a relation that says which object.
        assert!(said("go to the tv with the bed on your left").is_empty());
        assert!(said("the second chair from the left, then the tv").is_empty());
        assert!(said("go to the chair to the left of the table").is_empty());
        assert!(said("turn left, then the tv").is_empty());

        let plan = |step: &str| {
            format!("objects: [(sofa, None, black), (tv, None, None)]\nplan:\n{step}(get_obj(\"sofa\", #{{colour: \"black\"}}));\nmove_to_object(get_obj(\"tv\"));")
        };
        let says =
            "the person asked to stop left of the sofa, but the plan never calls move_to_left";
        let s = "stop to the left of the black sofa, then the tv";
        let f = findings(s, &plan("move_to_object"));
        assert!(
            f.iter()
                .any(|x| x.kind == FindingKind::Word && x.to_model.contains(says)),
            "{f:?}"
        );
        for other in ["move_to_right", "move_west"] {
            assert!(
                findings(s, &plan(other))
                    .iter()
                    .any(|x| x.to_model.contains(says)),
                "{other}"
            );
        }
        let f = findings(s, &plan("move_to_left"));
        assert!(f.iter().all(|x| !x.to_model.contains("stop left")), "{f:?}");
        // The side of another object is not the side of the sofa.
        let f = findings(
            s,
            "objects: [(sofa, None, black), (tv, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"black\"}));\nmove_to_left(get_obj(\"tv\"));",
        );
        assert!(f.iter().any(|x| x.to_model.contains(says)), "{f:?}");
        // Through a variable, and a side said of no named object.
        let f = findings(
            s,
            "objects: [(sofa, None, black), (tv, None, None)]\nplan:\nlet sofa = get_obj(\"sofa\", #{colour: \"black\"});\nmove_to_left(sofa);\nmove_to_object(get_obj(\"tv\"));",
        );
        assert!(f.iter().all(|x| !x.to_model.contains("stop left")), "{f:?}");
        let f = findings(
            "go to the tv, then just north of it",
            "objects: [(tv, None, None)]\nplan:\nmove_to_object(get_obj(\"tv\"));",
        );
        assert!(
            f.iter().any(|x| x.to_model.contains("stop north of, but")
                && x.to_user == "which object shall I stop on the north side of?"),
            "{f:?}"
        );
    }

    #[test]
    fn anchors_are_the_objects_named_in_a_clause_with_it() {
        let m = map();
        let said = |s: &str| anchors_said(&m, s, m.start_pose);
        let of = |s: &str, label: &str| {
            said(s)
                .into_iter()
                .find(|(l, _)| l == label)
                .map(|(_, a)| a)
        };
        let s = "go to the chair next to the black sofa, then whichever plant is nearest you";
        assert_eq!(of(s, "chair"), Some(vec!["sofa".to_string()]));
        assert_eq!(of(s, "sofa"), Some(vec!["chair".to_string()]));
        assert_eq!(of(s, "plant"), Some(vec![]));
        assert_eq!(of(s, "tv"), None);
        // Pointing back at an earlier clause; a synonym; the object named twice.
        assert_eq!(
            of("go to the bed, then the plant next to it", "plant"),
            Some(vec!["bed".to_string()])
        );
        assert_eq!(
            of("the chair by the couch", "chair"),
            Some(vec!["sofa".to_string()])
        );
        assert_eq!(
            of("the chair closest to the other chair", "chair"),
            Some(vec!["chair".to_string()])
        );
        // The check: an anchor of another clause is a finding, one of its own is not.
        let pick = |anchor: &str| {
            format!("objects: [(plant, None, None)]\nplan:\nmove_to_object(get_obj(\"plant\", #{{near: get_obj(\"{anchor}\")}}));\nmove_to_object(get_obj(\"tv\"));")
        };
        let f = findings("whichever plant is nearest you, then the tv", &pick("tv"));
        assert!(
            f.iter().any(|x| x.kind == FindingKind::Word
                && x.to_model
                    .contains("picks the plant near the tv, but the person did not say")),
            "{f:?}"
        );
        let f = findings("the plant next to the tv, then the tv", &pick("tv"));
        assert!(
            f.iter()
                .all(|x| !x.to_model.contains("did not say the plant")),
            "{f:?}"
        );
    }

    #[test]
    fn an_object_named_once_is_not_its_own_anchor() {
        let pick = |select: &str| {
            format!("objects: [(chair, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\", {select}));")
        };
        let said = "go to the chair nearest to you";
        let f = findings(said, &pick("#{near: get_obj(\"chair\", #{ordinal: 1})}"));
        assert!(
            f.iter().any(|x| x.kind == FindingKind::Word
                && x.to_model.contains("picks a chair near another chair")),
            "{f:?}"
        );
        assert!(findings(said, &pick("#{ordinal: 1}")).is_empty());
        // Named twice: the person may mean one chair near another.
        let f = findings(
            "go to the chair nearest to the red chair",
            "objects: [(chair, None, None), (chair, None, red)]\nplan:\nmove_to_object(get_obj(\"chair\", #{near: get_obj(\"chair\", #{colour: \"red\"})}));",
        );
        assert!(
            f.iter().all(|x| !x.to_model.contains("near another chair")),
            "{f:?}"
        );
    }

    #[test]
    fn an_anchor_said_once_after_what_it_picks_out_is_no_stop_of_its_own() {
        let both = "objects: [(plant, None, None), (tv, None, None)]\nplan:\nmove_to_object(get_obj(\"tv\"));\nmove_to_object(get_obj(\"plant\", #{near: get_obj(\"tv\")}));";
        let anchor = |f: &[Finding]| {
            f.iter().any(|x| {
                x.kind == FindingKind::Word && x.to_model.contains("must not also stop at the tv")
            })
        };
        // Held-out v3 (dev) hh03's form: the anchor made a stop of its own.
        let f = findings("go to the plant by the tv", both);
        assert!(anchor(&f), "{f:?}");
        assert_eq!(
            f.iter()
                .find(|x| x.to_model.contains("must not"))
                .map(|x| x.to_user.as_str()),
            Some("shall I stop at the tv too, or only at the plant near it?")
        );
        // Bound to a variable first, or a side of it: still a stop at the anchor.
        let bound = "objects: [(plant, None, None), (tv, None, None)]\nplan:\nlet t = get_obj(\"tv\");\nmove_to_left(t);\nmove_to_object(get_obj(\"plant\", #{near: get_obj(\"tv\")}));";
        assert!(anchor(&findings(
            "go to the plant closest to the television",
            bound
        )));
        // Said before what it picks out, said twice, or said later as a stop of its own
        // (the model made up the relation): a stop the person may want.
        for said in [
            "go to the tv, then the plant next to it",
            "go to the plant by the tv and then the tv",
            "go to the plant nearest to you, and then stand right in front of the tv",
            // The robot, or the next stop, between: held-out v7 (dev) hp13 and ho14.
            "go to the plant nearest to you, then the tv",
            "go to whichever plant is nearest u then the tv",
            "go to the plant by the bed, then the tv",
        ] {
            let f = findings(said, both);
            assert!(!anchor(&f), "{said}: {f:?}");
        }
        // The plan that only picks with it has nothing to find.
        let f = findings(
            "go to the plant by the tv",
            "objects: [(plant, None, None), (tv, None, None)]\nplan:\nmove_to_object(get_obj(\"plant\", #{near: get_obj(\"tv\")}));",
        );
        assert!(f.is_empty(), "{f:?}");
    }

    #[test]
    fn a_count_the_words_and_the_objects_line_give_is_one_the_plan_must_write() {
        let listed = |f: &[Finding]| {
            f.iter()
                .filter(|x| x.to_model.contains("the objects line counts the table"))
                .count()
        };
        // Held-out v16 (dev) vb11's form: "last" not after "the".
        let said = "go to the table that comes last when you go from west to east";
        let plan = |sel: &str| {
            format!("objects: [(table, last, None)]\nplan:\nmove_to_object(get_obj(\"table\", #{{{sel}}}));")
        };
        assert_eq!(listed(&findings(said, &plan("order: \"west_to_east\""))), 1);
        for right in [
            "ordinal: -1, order: \"west_to_east\"",
            "ordinal: 1, order: \"east_to_west\"",
        ] {
            assert_eq!(listed(&findings(said, &plan(right))), 0, "{right}");
        }
        // "Which is third", listed 3.
        let f = findings(
            "the table which is third from the west",
            "objects: [(table, 3, None, west_to_east)]\nplan:\nmove_to_object(get_obj(\"table\", #{order: \"west_to_east\"}));",
        );
        assert_eq!(listed(&f), 1, "{f:?}");
        // In more words: "one shy of the end" (held-out v15, dev, rb09's form).
        let f = findings(
            "counting the tables from the west, go to the table that's one shy of the end",
            "objects: [(table, 2, None, east_to_west)]\nplan:\nmove_to_object(get_obj(\"table\", #{ordinal: 2}));",
        );
        assert_eq!(listed(&f), 1, "{f:?}");
        // The line lists no count, "last" says when, or the clause names two objects:
        // nothing to find here.
        for (said, line) in [
            (
                "go to the table that comes last when you go from west to east",
                "(table, None, None)",
            ),
            ("and the table last", "(table, last, None)"),
            (
                "the table that comes last by the sofa",
                "(table, last, None), (sofa, None, None)",
            ),
        ] {
            let f = findings(
                said,
                &format!("objects: [{line}]\nplan:\nmove_to_object(get_obj(\"table\"));"),
            );
            assert_eq!(listed(&f), 0, "{said}: {f:?}");
        }
    }

    #[test]
    fn the_last_chair_but_one_counts_the_chair_second_from_the_end() {
        // Held-out v14 (dev) pb09 and pc04's form: the name between "last" and "but".
        let said = "stop at the last chair but one; next the table";
        let plan = |sel: &str| {
            format!("objects: [(chair, 2, None), (table, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{{{sel}}}));\nmove_to_object(get_obj(\"table\"));")
        };
        let counted = |f: &[Finding]| {
            f.iter()
                .filter(|x| x.to_model.contains("has ordinal -2"))
                .map(|x| x.about.clone())
                .collect::<Vec<_>>()
        };
        assert_eq!(
            counted(&findings(said, &plan("ordinal: 1"))),
            [Some(About::Label("chair".into()))]
        );
        assert!(counted(&findings(said, &plan("ordinal: -2"))).is_empty());
        // Said from either end, as "second to last" is.
        assert_eq!(counts_said(said), [2]);
    }

    #[test]
    fn a_stop_between_two_objects_the_plan_lacks_is_found_at_the_first_of_them() {
        let between = |said: &str, answer: &str| {
            findings(said, answer)
                .into_iter()
                .find(|x| x.to_model.contains("stops between nothing"))
                .map(|x| x.about)
        };
        // Held-out v16 (dev) vc10's form.
        let plan = "objects: [(sofa, None, None), (chair, None, black), (tv, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\"));\nmove_to_object(get_obj(\"chair\", #{colour: \"black\"}));\nmove_to_object(get_obj(\"tv\"));";
        let said = "go to the sofa, then wait between the black chair and the tv";
        assert_eq!(
            between(said, plan),
            Some(Some(About::Label("chair".into())))
        );
        let m = map();
        let a = parse_answer(plan).unwrap();
        let f = check_answer(&m, said, &a.tuples, &a.plan, m.start_pose, &[], &[]);
        assert_eq!(
            first_disputed_step(&m, said, &f, &a.plan, m.start_pose),
            Some(1)
        );
        // Said twice: no one place.
        assert_eq!(
            between(
                "go between the sofa and the tv, then between the chair and the bed",
                plan
            ),
            Some(None)
        );
    }

    #[test]
    fn two_stops_at_what_one_clause_names_once_each_are_a_finding() {
        // Held-out v16 (dev) va05's form: no `near:`, a stop at each.
        let two = "objects: [(plant, None, None), (tv, None, None)]\nplan:\nmove_to_object(get_obj(\"plant\"));\nmove_to_object(get_obj(\"tv\"));";
        let anchor = |f: &[Finding]| {
            f.iter()
                .filter(|x| x.to_model.contains("do not stop at the tv itself"))
                .map(|x| x.bar.clone())
                .collect::<Vec<_>>()
        };
        for said in [
            "go to the plant next to the tv",
            "robot, the bed first, then the plant right by the black tv",
        ] {
            assert_eq!(
                anchor(&findings(said, two)),
                [Some(Bar::AnchorStop { label: "tv".into() })],
                "{said}"
            );
        }
        // A side of it is a stop at it too.
        let side = "objects: [(plant, None, None), (tv, None, None)]\nplan:\nmove_to_left(get_obj(\"plant\"));\nmove_to_object(get_obj(\"tv\"));";
        assert_eq!(
            anchor(&findings("stop left of the plant by the tv", side)).len(),
            1
        );
        // Two clauses, the robot between, far apart, a pair, a name said twice, or a
        // face: the stops may be what was asked.
        for said in [
            "go to the plant, the tv",
            "go to the plant and the tv",
            "the plant closest to you then the tv",
            "the plant nearest to me by the tv",
            "the plant in the corner of the big living room by the tv",
            "go between the plant near the tv",
            "the plant by the tv, then the tv again",
        ] {
            assert!(anchor(&findings(said, two)).is_empty(), "{said}");
        }
        let face = "objects: [(plant, None, None), (tv, None, None)]\nplan:\nmove_to_object(get_obj(\"plant\"));\nface(get_obj(\"tv\"));";
        assert!(anchor(&findings("wait at the plant facing the tv", face)).is_empty());
    }

    #[test]
    fn the_directions_said_are_the_orders_the_words_count_in() {
        use ObjectOrder::*;
        let said = |s: &str| directions_said(s);
        // A count from a side, from its start or, counted from the end, from the other.
        assert_eq!(said("the 2nd seat from the west"), Some(vec![WestToEast]));
        assert_eq!(
            said("to do: 2nd to last teller desk from the west; a white table"),
            Some(vec![EastToWest])
        );
        assert_eq!(
            said("the penultimate lamp from the east"),
            Some(vec![WestToEast])
        );
        assert_eq!(
            said("counting from the north, the third bin"),
            Some(vec![NorthToSouth])
        );
        // "The last ... from the west" is -1 from the west or 1 from the east.
        assert_eq!(
            said("the last seat counting from the west"),
            Some(vec![EastToWest, WestToEast])
        );
        // Superlatives and "furthest" + a side.
        assert_eq!(said("the westernmost shelf"), Some(vec![WestToEast]));
        assert_eq!(
            said("the speaker furthest to the east, then the leftmost chair"),
            Some(vec![EastToWest, LeftToRight])
        );
        // A side move counts in no order; no direction, none.
        assert_eq!(said("stop on the north side of the table"), Some(vec![]));
        assert_eq!(
            said("park left of the sofa, then the third chair from the right"),
            Some(vec![RightToLeft])
        );
        assert_eq!(said("the third chair"), Some(vec![]));
        // A direction no count reads: nothing to narrow.
        assert_eq!(said("the chair on your left"), None);
        assert_eq!(said("the north-east corner chair"), None);
        assert_eq!(said("the chair from the west"), None);
    }

    #[test]
    fn a_typed_colour_keeps_its_first_letter_and_a_short_one_only_swaps_two() {
        for (instruction, colour) in [
            ("the blak chair", "black"),
            ("the balck chair", "black"),
            ("the whiet sofa", "white"),
            ("a gren plant", "green"),
            ("the rde chair", "red"),
            ("the purpel lamp", "purple"),
            ("the grey chair", "gray"),
        ] {
            assert!(
                colour_said(instruction, &[])(colour),
                "{instruction}: {colour}"
            );
        }
        for (instruction, colour) in [
            ("the camp bed", "red"),
            ("the sofa rather than the chair", "tan"),
            ("the camper van", "tan"),
            ("the fish tank", "tan"),
            ("the scrub sink", "pink"),
            ("the cold store", "gold"),
            ("read the sign", "red"),
            // Everyday words one edit from a colour ([`EVERYDAY_NEAR_COLOURS`]).
            ("then come back", "black"),
            ("can you go to the desk", "cyan"),
            ("the tea urn", "teal"),
            ("good, now the sofa", "gold"),
            ("the server rack", "silver"),
            ("pick the nearest chair", "pink"),
        ] {
            assert!(
                !colour_said(instruction, &[])(colour),
                "{instruction}: {colour}"
            );
        }
        // A typo one letter dropped still reads.
        assert!(colour_said("the blck chair, then come back", &[])("black"));
    }

    #[test]
    fn a_count_from_a_side_is_counted_from_that_side() {
        // Held-out v3 (dev): "the second red chair counting from the west" counted from
        // the east passed every check.
        for (instruction, select, says) in [
            (
                "go to the second red chair counting from the west",
                "#{ordinal: 2, colour: \"red\", order: \"east_to_west\"}",
                "said \"second red chair counting from the west\": that is ordinal: 2 with order \"west_to_east\"",
            ),
            (
                "counting from the left, go to the third chair",
                "#{ordinal: 3, order: \"right_to_left\"}",
                "said \"counting from the left go to the third\": that is ordinal: 3 with order \"left_to_right\"",
            ),
            (
                "go to the second to last chair from the north",
                "#{ordinal: 2, order: \"north_to_south\"}",
                "that is ordinal: 2 with order \"south_to_north\"",
            ),
            (
                "the last chair from the east",
                "#{ordinal: 1, order: \"east_to_west\"}",
                "said \"last chair from the east\": that is ordinal: 1 with order \"west_to_east\"",
            ),
            // The count must be on some target: a side with no count at all.
            (
                "the second chair from the south",
                "#{ordinal: 2}",
                "that is ordinal: 2 with order \"south_to_north\"",
            ),
            // A count from the end begun six words before "from" (held-out v11, dev,
            // lc09).
            (
                "the second from last red chair counting from the west",
                "#{ordinal: 2, colour: \"red\", order: \"west_to_east\"}",
                "said \"second from last red chair counting from the west\": that is ordinal: 2 with order \"east_to_west\"",
            ),
        ] {
            assert_word_finding(instruction, "chair", select, says);
        }
        for (instruction, select) in [
            (
                "go to the second red chair counting from the west",
                "#{ordinal: 2, colour: \"red\", order: \"west_to_east\"}",
            ),
            (
                "go to the second to last chair from the north",
                "#{ordinal: 2, order: \"south_to_north\"}",
            ),
            (
                "the last chair from the east",
                "#{ordinal: 1, order: \"west_to_east\"}",
            ),
            // An unwritten ordinal is the first (held-out v7, dev, hq14).
            (
                "1) first chair from the east 2) the sofa",
                "#{order: \"east_to_west\"}",
            ),
            (
                "the second from last red chair counting from the west",
                "#{ordinal: 2, colour: \"red\", order: \"east_to_west\"}",
            ),
            (
                "the second to last red chair counting from the west",
                "#{ordinal: -2, colour: \"red\", order: \"west_to_east\"}",
            ),
            // No count near: "from the west" says nothing to count.
            ("go to the chair, coming from the west", "#{ordinal: 1}"),
            ("walk over from the kitchen to the chair", "#{ordinal: 1}"),
        ] {
            let f = findings_for_pick(instruction, "chair", select);
            assert!(
                !f.iter()
                    .any(|x| x.to_model.contains("no object in the plan is counted so")),
                "{instruction} {select}: {f:?}"
            );
        }
    }

    #[test]
    fn a_count_from_the_end_may_be_said_of_a_side_only() {
        for (instruction, of_sides) in [
            ("the shelf furthest north, then the red chair", true),
            // A side a word or two after "furthest" ([`side_after`]).
            (
                "the chair furthest to the left, the desk farthest south",
                true,
            ),
            ("the chair furthest from you on the left", false),
            ("the second to last shelf from the west", false),
            (
                "the desk furthest south, the last chair from the left",
                false,
            ),
            ("the farthest bin, then the shelf furthest north", false),
            ("the last chair, then the shelf furthest north", false),
            ("the table furthest from you", false),
            ("the last shelf, the one from the kitchen", false),
            // Each word far_end_said reads as the far end keeps the bar off.
            (
                "the most distant chair, then the shelf furthest north",
                false,
            ),
            ("the chair far away, then the shelf furthest north", false),
            ("the shelf furthest north, then the furthermost bin", false),
        ] {
            assert_eq!(
                ends_said_of_sides(&words(instruction)),
                of_sides,
                "{instruction}"
            );
        }
    }

    #[test]
    fn penultimate_counts_from_the_end() {
        // Qwen 1.5B on people.nav: "the penultimate plant from the west" as the first.
        let f = findings(
            "then the penultimate plant from the west",
            "objects: [(plant, 2, None, west_to_east)]\nplan:\nmove_to_object(get_obj(\"plant\", #{ordinal: 1, order: \"west_to_east\"}));",
        );
        assert!(
            f.iter().any(|x| x
                .to_model
                .contains("has ordinal -2 (or 2 counted from the other end)")),
            "{f:?}"
        );
        // (2 east to west is the same plant, but "penultimate" says -2: the unsaid-count
        // check and the grammar offer only that.)
        let f = findings(
            "then the penultimate plant from the west",
            "objects: [(plant, 2, None, west_to_east)]\nplan:\nmove_to_object(get_obj(\"plant\", #{ordinal: -2, order: \"west_to_east\"}));",
        );
        assert!(f.is_empty(), "{f:?}");
        // The second from the west is not the penultimate from the west.
        let f = findings(
            "then the penultimate plant from the west",
            "objects: [(plant, 2, None, west_to_east)]\nplan:\nmove_to_object(get_obj(\"plant\", #{ordinal: 2, order: \"west_to_east\"}));",
        );
        assert!(
            f.iter().any(|x| x.to_model.contains(
                "said \"penultimate plant from the west\": that is ordinal: 2 with order \"east_to_west\""
            )),
            "{f:?}"
        );
        // The second nearest is not the penultimate.
        let f = findings(
            "the penultimate plant",
            "objects: [(plant, 2, None)]\nplan:\nmove_to_object(get_obj(\"plant\", #{ordinal: 2}));",
        );
        assert!(!f.is_empty());
    }

    #[test]
    fn a_direction_the_person_did_not_say_is_found() {
        // Qwen 1.5B on people.nav: "chair number 3" counted north to south.
        let f = findings(
            "then chair number 3",
            "objects: [(chair, 3, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 3, order: \"north_to_south\"}));",
        );
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(f[0].to_model.contains("named no direction"), "{f:?}");
        // A direction said in any form is not a finding.
        for instruction in [
            "the third chair from the north",
            "the westernmost chair, number 3",
            "the third chair on the left",
        ] {
            let f = findings(
                instruction,
                "objects: [(chair, 3, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 3, order: \"north_to_south\"}));",
            );
            assert!(
                f.iter().all(|x| !x.to_model.contains("named no direction")),
                "{instruction}: {f:?}"
            );
        }
    }

    #[test]
    fn a_region_the_plan_stops_in_is_accounted_for() {
        // "the yellow table in the kitchen", answered without the region: the dry run
        // stops at a yellow table in the kitchen, so the room is not asked about.
        let m = map();
        let kitchen = m.regions.iter().find(|r| r.name == "kitchen").unwrap();
        let inside = m
            .instances
            .iter()
            .find(|i| i.label != "wall" && kitchen.polygon.contains(i.centroid))
            .expect("flat-a has an object in the kitchen");
        let outside = m
            .instances
            .iter()
            .find(|i| i.label == inside.label && !kitchen.polygon.contains(i.centroid));
        let answer = format!(
            "objects: [({0}, None, None), (kitchen, None, None)]\nplan:\nmove_to_object(get_obj(\"{0}\"));",
            inside.label
        );
        let a = parse_answer(&answer).unwrap();
        let instruction = format!("go to the {} in the kitchen", inside.label);
        let asked = |visited: &[u32]| {
            check_answer(
                &m,
                &instruction,
                &a.tuples,
                &a.plan,
                m.start_pose,
                visited,
                &[],
            )
            .iter()
            .any(|x| x.to_user.contains("kitchen"))
        };
        assert!(!asked(&[inside.id]));
        if let Some(o) = outside {
            assert!(asked(&[o.id]));
        }
        assert!(asked(&[]));
        // Said as a stop of its own, the kitchen is not visited by a stop at an object
        // that stands in it but is said elsewhere (held-out v15, dev, rc02's form).
        let other = m
            .instances
            .iter()
            .find(|i| {
                i.label != "wall"
                    && i.label != inside.label
                    && !kitchen.polygon.contains(i.centroid)
                    && m.instances
                        .iter()
                        .filter(|j| j.label == i.label)
                        .all(|j| !kitchen.polygon.contains(j.centroid))
            })
            .expect("flat-a has an object outside the kitchen");
        let answer = format!(
            "objects: [({0}, None, None), ({1}, None, None), (kitchen, None, None)]\nplan:\nmove_to_object(get_obj(\"{0}\"));\nmove_to_object(get_obj(\"{1}\"));",
            inside.label, other.label
        );
        let a = parse_answer(&answer).unwrap();
        let said = |tail: &str| {
            let instruction = format!("go to the {}, then the {}{tail}", inside.label, other.label);
            check_answer(
                &m,
                &instruction,
                &a.tuples,
                &a.plan,
                m.start_pose,
                &[inside.id, other.id],
                &[],
            )
            .iter()
            .any(|x| x.to_user.contains("kitchen"))
        };
        assert!(said(", and end up back in the kitchen"));
        assert!(!said(""));
    }

    #[test]
    fn the_room_the_robot_starts_in_named_first_is_no_stop_to_make() {
        // Held-out v10 (dev) kb14's form; flat-a's robot starts in the living room.
        let m = map();
        let asked = |instruction: &str, line: &str, pose: Pose| {
            let answer = format!(
                "objects: [{line}]\nplan:\nmove_to_object(get_obj(\"table\"));\nmove_to_start();"
            );
            let a = parse_answer(&answer).unwrap();
            check_answer(&m, instruction, &a.tuples, &a.plan, pose, &[], &[])
                .iter()
                .any(|x| x.to_model.contains("living room"))
        };
        let start = m.start_pose;
        let said = "Starting from the living room: the table, then back to where you started";
        assert!(!asked(said, "(table, None, None)", start));
        assert!(!asked(
            said,
            "(living room, None, None), (table, None, None)",
            start
        ));
        // Named after an object, or where the robot is elsewhere, it is a request.
        assert!(asked(
            "the table, then the living room, then back to where you started",
            "(table, None, None)",
            start
        ));
        let kitchen = Pose::new(11.0, 2.0, 0.0);
        assert!(asked(said, "(table, None, None)", kitchen));
    }

    #[test]
    fn a_colour_the_person_did_not_say_is_found() {
        // A made-up colour that excludes an instance of the object.
        let f = findings(
            "go to the chair",
            "objects: [(chair, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{not_colour: \"black\"}));",
        );
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!(f[0].kind, FindingKind::Word);
        assert!(f[0].to_model.contains("not_colour \"black\""), "{f:?}");
        assert_eq!(f[0].to_user, "do you mean a chair that is not black?");
        // The re-ask bars the chair's unsaid colours.
        let chair = Some(Bar::UnsaidColours {
            label: "chair".into(),
        });
        assert_eq!(f[0].bar, chair, "{f:?}");
        let f = findings(
            "go to the couch",
            "objects: [(couch, None, None)]\nplan:\nmove_to_object(get_obj(\"couch\", #{colour: \"red\"}));",
        );
        assert!(
            f.iter().any(|x| x.to_user == "do you mean a red couch?"
                && x.bar
                    == Some(Bar::UnsaidColours {
                        label: "sofa".into()
                    })),
            "the bar names the map's label: {f:?}"
        );
        // A colour that excludes nothing (flat-a has one fridge, a silver one) and the
        // colours that tell apart the two objects one stops between are not findings.
        for answer in [
            "objects: [(fridge, None, None)]\nplan:\nmove_to_object(get_obj(\"fridge\", #{not_colour: \"white\"}));",
            "objects: [(fridge, None, None)]\nplan:\nmove_to_object(get_obj(\"fridge\", #{colour: \"silver\"}));",
        ] {
            assert!(findings("go to the fridge", answer).is_empty(), "{answer}");
        }
        let f = findings(
            "stop between the two sofas",
            "objects: [(sofa, None, None)]\nplan:\nmove_in_between(get_obj(\"sofa\", #{colour: \"black\"}), get_obj(\"sofa\", #{colour: \"red\"}));",
        );
        assert!(
            f.iter().all(|x| !x.to_model.contains("did not say")),
            "{f:?}"
        );
        let f = findings(
            "go to the fridge",
            "objects: []\nplan:\nmove_to_object(get_obj(\"fridge\"));",
        );
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!(f[0].kind, FindingKind::Parts);
        assert!(f[0].to_model.contains("objects line is empty"), "{f:?}");
        // In a conversation, the colours of what was visited are known: "the other one"
        // after the red sofa is the sofa that is not red.
        let m = map();
        let red = m
            .instances
            .iter()
            .find(|i| i.label == "sofa" && i.colour.as_deref() == Some("red"))
            .expect("flat-a has a red sofa");
        let a = parse_answer(
            "objects: [(sofa, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{not_colour: \"red\"}));",
        )
        .unwrap();
        let f = check_answer(
            &m,
            "now the other one",
            &a.tuples,
            &a.plan,
            m.start_pose,
            &[],
            &[red.id],
        );
        assert!(
            f.iter().all(|x| !x.to_model.contains("did not say")),
            "{f:?}"
        );
        // Said colours, in any spelling or position, are not findings.
        for (instruction, answer) in [
            (
                "go to the sofa, the red one",
                "objects: [(sofa, None, red)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));",
            ),
            (
                "go to the sofa that isn't black",
                "objects: [(sofa, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{not_colour: \"black\"}));",
            ),
            (
                "pls go too the secnd blak chiar",
                "objects: [(chair, 2, black)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 2, colour: \"black\"}));",
            ),
            (
                "go to the gray chair",
                "objects: [(chair, None, grey)]\nplan:\nmove_to_object(get_obj(\"chair\", #{colour: \"grey\"}));",
            ),
        ] {
            let f = findings(instruction, answer);
            assert!(
                f.iter().all(|x| !x.to_model.contains("did not say")),
                "{instruction}: {f:?}"
            );
        }
    }

    #[test]
    fn a_name_the_plan_leaves_out_is_found() {
        // SmolLM2's answer to "go to the red sofa": an empty objects line and a bathtub.
        let f = findings(
            "go to the red sofa",
            "objects: []\nplan:\nmove_to_object(get_obj(\"bathtub\", #{not_colour: \"red\"}));",
        );
        assert!(
            f.iter()
                .any(|x| x.kind == FindingKind::Word && x.to_model.contains("\"sofa\"")),
            "{f:?}"
        );
        // A name said as an anchor, a room or in the plural is used when the plan picks
        // it there; a two-word name is one name.
        for (instruction, answer) in [
            (
                "go to the chair next to the black table",
                "objects: [(chair, None, None), (table, None, black)]\nplan:\nmove_to_object(get_obj(\"chair\", #{near: get_obj(\"table\", #{colour: \"black\"})}));",
            ),
            (
                "stop between the two sofas",
                "objects: [(sofa, None, None)]\nplan:\nmove_between_the_two(\"sofa\");",
            ),
            (
                "go to the chair in the kitchen",
                "objects: [(chair, None, None), (kitchen, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{region: \"kitchen\"}));",
            ),
            (
                "go to the living room",
                "objects: [(living room, None, None)]\nplan:\nmove_to_object(\"living room\");",
            ),
        ] {
            let f = findings(instruction, answer);
            assert!(
                f.iter().all(|x| !x.to_model.contains("neither goes to")),
                "{instruction}: {f:?}"
            );
        }
        let m = map();
        let said = said_names(&m, &words("the living room, then the sofas and the tv"));
        let labels: Vec<&str> = said.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["living room", "sofa", "tv"]);
    }

    #[test]
    fn a_dropped_colour_is_found_not_fixed() {
        let f = findings(
            "go to the sofa, the red one",
            "objects: [(sofa, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\"));",
        );
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!(f[0].kind, FindingKind::Word);
        assert!(f[0].to_model.contains("\"red\""), "{}", f[0].to_model);
    }

    #[test]
    fn a_dropped_ordinal_and_farthest_are_found() {
        let f = findings(
            "go to chair number 2 then the farthest plant",
            "objects: [(chair, 2, None), (plant, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\"));\nmove_to_object(get_obj(\"plant\"));",
        );
        assert!(
            f.iter().any(|x| x.to_model.contains("\"farthest\"")),
            "{f:?}"
        );
        assert!(
            f.iter().any(|x| x.to_model.contains("\"number 2\"")),
            "{f:?}"
        );
    }

    #[test]
    fn unknown_objects_and_colours_the_map_lacks() {
        let f = findings(
            "go to the piano",
            "objects: [(piano, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\"));",
        );
        assert_eq!(f[0].kind, FindingKind::UnknownObject, "{f:?}");
        assert!(f[0].to_user.contains("piano"), "{f:?}");
        // Where a clause sends the robot back and names nothing on the map, its words
        // name the start (held-out v14, dev, pa10's form), for a plan that moves back.
        let back = |said: &str| {
            findings(
                said,
                "objects: [(sofa, None, None), (spawn point, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\"));\nmove_to_start();",
            )
            .into_iter()
            .any(|x| x.kind == FindingKind::UnknownObject)
        };
        assert!(!back("go to the sofa, and then back to your spawn point"));
        assert!(back("go to the sofa, then the spawn point, then come back"));
        // A count word, or a part of a map name the person said, listed as an object
        // is the line's misreading, not an object the map lacks (held-out v14 pb04's and
        // v15 rc13's forms, dev).
        let unknown = |said: &str, listed: &str| {
            findings(
                said,
                &format!("objects: [({listed}, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{{ordinal: 2}}));"),
            )
            .into_iter()
            .any(|x| x.kind == FindingKind::UnknownObject)
        };
        assert!(!unknown("go to the second chair", "second"));
        assert!(!unknown("the chair in the living room", "living"));
        assert!(unknown("go to the second chair, then the piano", "piano"));
        let f = findings(
            "go to the purple sofa",
            "objects: [(sofa, None, purple)]\nplan:\nmove_to_object(get_obj(\"sofa\"));",
        );
        assert!(f.iter().any(|x| x.kind == FindingKind::NotOnMap), "{f:?}");
    }

    #[test]
    fn two_of_more_than_two_picked_by_their_counts_are_a_guess() {
        let two = |f: &[Finding]| {
            f.iter()
                .filter(|x| x.to_model.contains("move_between_the_two"))
                .count()
        };
        // flat-a: 3 black chairs of 8, 2 yellow tables of 4.
        let f = findings(
            "go between the two black chairs",
            "objects: [(chair, None, black)]\nplan:\nmove_in_between(get_obj(\"chair\", #{ordinal: 1, colour: \"black\"}), get_obj(\"chair\", #{ordinal: 2, colour: \"black\"}));",
        );
        assert_eq!(two(&f), 1, "{f:?}");
        let q = f
            .iter()
            .find(|x| x.to_model.contains("move_between_the_two"))
            .unwrap();
        assert!(q.to_model.contains("3 match here"), "{q:?}");
        assert!(
            q.to_model
                .contains("move_between_the_two(\"chair\", #{colour: \"black\"})"),
            "{q:?}"
        );
        assert_eq!(
            q.to_user,
            "\"the two black chairs\" names 3 here: which two do you mean?"
        );
        // Exactly two match: those are the two.
        let f = findings(
            "go between the two yellow tables",
            "objects: [(table, None, yellow)]\nplan:\nmove_in_between(get_obj(\"table\", #{ordinal: 1, colour: \"yellow\"}), get_obj(\"table\", #{ordinal: 2, colour: \"yellow\"}));",
        );
        assert_eq!(two(&f), 0, "{f:?}");
        // Told apart by their colours, or not said to be two: not a guess at two.
        let f = findings(
            "go between the red chair and the black chair",
            "objects: [(chair, None, red), (chair, None, black)]\nplan:\nmove_in_between(get_obj(\"chair\", #{colour: \"red\"}), get_obj(\"chair\", #{colour: \"black\"}));",
        );
        assert_eq!(two(&f), 0, "{f:?}");
        let f = findings(
            "go between the first and the second black chair",
            "objects: [(chair, 1, black), (chair, 2, black)]\nplan:\nmove_in_between(get_obj(\"chair\", #{ordinal: 1, colour: \"black\"}), get_obj(\"chair\", #{ordinal: 2, colour: \"black\"}));",
        );
        assert_eq!(two(&f), 0, "{f:?}");
    }

    #[test]
    fn a_label_is_always_coloured_when_each_mention_has_a_colour_before_it() {
        let m = map();
        let always = |i: &str| labels_always_coloured(&m, i, m.start_pose);
        assert_eq!(
            always("go to the yellow table closest to the counter"),
            ["table"]
        );
        assert_eq!(always("the red chair, then the black chair"), ["chair"]);
        assert_eq!(
            always("the white table, then the plant closest to the sink"),
            ["table"]
        );
        assert!(always("the red chair, then another chair").is_empty());
        assert!(always("the sofa, the red one").is_empty());
        assert!(always("go to the chair painted red").is_empty());
        assert_eq!(
            always("the dark red sofa and the green plant"),
            ["plant", "sofa"]
        );
    }

    #[test]
    fn coming_back_is_read_where_the_words_ask_for_it() {
        for yes in [
            "go to the sofa and come back here",
            "go to the sofa, then come back",
            "go to the sofa and then come back please",
            "the sofa then get back here",
            "go to the sofa and back to where you started",
            "then back to where we started",
            "go to the fridge, then return",
            "go to the fridge and return to the start",
            "head back to your starting point",
            "go back to the start",
            "go to the bed then go back, thanks",
            "Go to the sofa. Come back!",
        ] {
            assert!(return_said(yes), "{yes}");
        }
        for no in [
            "go to the sofa",
            "go back to the table you just visited",
            "come back to the kitchen",
            "go to the sofa and come to the chair",
            "return to the red sofa",
            "the chair at the back of the room",
            "go to the backpack",
            "where is the sofa",
            "go to the sofa where the chair is",
        ] {
            assert!(!return_said(no), "{no}");
        }
    }

    #[test]
    fn a_colour_said_after_a_name_across_a_comma_is_that_names() {
        // Held-out v13 (dev) nb06's shape on flat-a: the red is the sofa's, so the
        // objects line's red desk (the map has none) is the model's note, and the plan
        // is judged on its own.
        let f = findings(
            "the sofa, the red one, then the desk in the office",
            "objects: [(sofa, None, red), (desk, None, red), (office, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));\nmove_to_object(get_obj(\"desk\", #{region: \"office\"}));",
        );
        assert!(f.iter().all(|x| x.kind != FindingKind::NotOnMap), "{f:?}");
        // Said of the desk itself, it is one the map lacks.
        let f = findings(
            "the sofa, then the red desk in the office",
            "objects: [(sofa, None, None), (desk, None, red), (office, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\"));\nmove_to_object(get_obj(\"desk\", #{region: \"office\"}));",
        );
        assert!(f.iter().any(|x| x.kind == FindingKind::NotOnMap), "{f:?}");
        // Said after another name, of none the words read (held-out v14, dev, pa09's
        // form): the line's purple desk is a note while the plan's desk has no colour;
        // a plan that picks a purple desk is one the map lacks.
        let said = "the desk in the office, then the sofa painted purple";
        let note = "objects: [(desk, None, purple), (office, None, None), (sofa, None, None)]\nplan:\nmove_to_object(get_obj(\"desk\", #{region: \"office\"}));\nmove_to_object(get_obj(\"sofa\"));";
        let f = findings(said, note);
        assert!(f.iter().all(|x| x.kind != FindingKind::NotOnMap), "{f:?}");
        let carried = "objects: [(desk, None, purple), (office, None, None), (sofa, None, None)]\nplan:\nmove_to_object(get_obj(\"desk\", #{colour: \"purple\"}));\nmove_to_object(get_obj(\"sofa\"));";
        let f = findings(said, carried);
        assert!(f.iter().any(|x| x.kind == FindingKind::NotOnMap), "{f:?}");
    }

    #[test]
    fn a_stop_at_an_object_nobody_named_is_a_finding_at_its_step() {
        // Held-out v13 (dev) na11's shape on flat-a: a room said, an object in it picked.
        let f = findings(
            "go to the red sofa, then the kitchen",
            "objects: [(sofa, None, red), (kitchen, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));\nmove_to_object(get_obj(\"fridge\", #{region: \"kitchen\"}));",
        );
        let unnamed: Vec<&Finding> = f
            .iter()
            .filter(|x| x.to_model.contains("never named a fridge"))
            .collect();
        assert_eq!(unnamed.len(), 1, "{f:?}");
        assert_eq!(unnamed[0].about, Some(About::Step(1)));
        // The re-ask may not stop at a fridge again.
        assert_eq!(
            unnamed[0].bar,
            Some(Bar::AnchorStop {
                label: "fridge".into()
            })
        );
        assert!(unnamed[0].to_model.contains("move_to_object(\"kitchen\")"));
        // An object said by a synonym or a typo is named; so is a room.
        for (said, pick) in [
            ("go to the couch", "get_obj(\"sofa\")"),
            ("go to the sofaa", "get_obj(\"sofa\")"),
            ("go to the kitchen", "\"kitchen\""),
        ] {
            let f = findings(
                said,
                &format!("objects: [(sofa, None, None)]\nplan:\nmove_to_object({pick});"),
            );
            assert!(
                f.iter().all(|x| !x.to_model.contains("never named")),
                "{said}: {f:?}"
            );
        }
        // An anchor nobody named is an object the plan goes to as well.
        let f = findings(
            "go to the red sofa",
            "objects: [(sofa, None, red)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\", near: get_obj(\"tv\")}));",
        );
        assert!(
            f.iter().any(|x| x.to_model.contains("never named one")),
            "{f:?}"
        );
    }

    #[test]
    fn an_object_named_twice_and_picked_once_is_a_finding() {
        let twice = |f: &[Finding]| {
            f.iter()
                .any(|x| x.to_model.contains("named the sofa 2 times"))
        };
        // Held-out v13 (dev) na04's shape on flat-a.
        let f = findings(
            "Stop A: the black sofa. Stop B: the tv. Stop C: the red sofa.",
            "objects: [(sofa, None, red), (tv, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));\nmove_to_object(get_obj(\"tv\"));",
        );
        assert!(twice(&f), "{f:?}");
        let f = findings(
            "Stop A: the black sofa. Stop B: the tv. Stop C: the red sofa.",
            "objects: [(sofa, None, black), (tv, None, None), (sofa, None, red)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"black\"}));\nmove_to_object(get_obj(\"tv\"));\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));",
        );
        assert!(!twice(&f), "{f:?}");
        // Named twice, once to pick out another: the anchor counts.
        let f = findings(
            "the chair next to the red sofa, then the black sofa",
            "objects: [(chair, None, None), (sofa, None, red), (sofa, None, black)]\nplan:\nmove_to_object(get_obj(\"chair\", #{near: get_obj(\"sofa\", #{colour: \"red\"})}));\nmove_to_object(get_obj(\"sofa\", #{colour: \"black\"}));",
        );
        assert!(!twice(&f), "{f:?}");
        // The last word of a name alone is no mention of it: held-out v16 (dev) vb05 on
        // its scene, "stand" there is what the robot does.
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/scenes/florist-aq.scene.json"
        );
        let m = IvlMap::from_scene(&map_core::scene::Scene::from_path(path).unwrap());
        let said = |instruction: &str| {
            let a = parse_answer(
                "objects: [(cactus stand, None, None)]\nplan:\nmove_to_object(get_obj(\"cactus stand\"));",
            )
            .unwrap();
            check_answer(&m, instruction, &a.tuples, &a.plan, m.start_pose, &[], &[])
                .iter()
                .any(|x| x.to_model.contains("named the cactus stand 2 times"))
        };
        assert!(!said("go and stand centred there, then the cactus stand"));
        // The room the robot is in, said first, is no mention of a stop.
        let room = m
            .regions
            .iter()
            .find(|r| r.polygon.contains(m.start_pose.position))
            .map(|r| r.name.clone())
            .unwrap();
        let twice = |instruction: &str| {
            let a = parse_answer(&format!(
                "objects: [(cactus stand, None, None)]\nplan:\nmove_to_object(get_obj(\"cactus stand\", #{{region: \"{room}\"}}));"
            ))
            .unwrap();
            check_answer(&m, instruction, &a.tuples, &a.plan, m.start_pose, &[], &[])
                .iter()
                .any(|x| x.to_model.contains(&format!("named the {room} 2 times")))
        };
        assert!(!twice(&format!(
            "we're in the {room}. go to the cactus stand in the {room}"
        )));
        assert!(twice(&format!(
            "the cactus stand in the {room}, then the {room} again"
        )));
        assert!(said("the cactus stand, then the cactus stand again"));
        assert!(said("the cactus stand, then the other cactus stands"));
    }

    #[test]
    fn a_direction_counted_in_that_no_tuple_lists_is_found() {
        let unlisted = |instruction: &str, line: &str| -> Vec<&str> {
            orders_unlisted(instruction, &crate::tuples::parse_tuples(line).unwrap())
                .into_iter()
                .map(ObjectOrder::name)
                .collect()
        };
        // Held-out v13 (dev) nx05 and nx06.
        assert_eq!(
            unlisted(
                "scurry over to the farthest-east front loader",
                "[(front loader, None, None)]"
            ),
            ["east_to_west"]
        );
        assert_eq!(
            unlisted(
                "the westernmost blue dome seat please",
                "[(dome seat, None, blue)]"
            ),
            ["west_to_east"]
        );
        assert!(unlisted(
            "the westernmost blue dome seat please",
            "[(dome seat, 1, blue, west_to_east)]"
        )
        .is_empty());
        // Counted from the other end is listed too ("the second to last from the west").
        assert!(unlisted(
            "the second to last chair from the west",
            "[(chair, 2, None, east_to_west)]"
        )
        .is_empty());
        // No direction, or a side of a side move: nothing.
        assert!(unlisted("the third chair", "[(chair, 3, None)]").is_empty());
        assert!(unlisted("the north side of the sofa", "[(sofa, None, None)]").is_empty());
    }

    #[test]
    fn sent_back_to_no_named_place_is_coming_back() {
        let m = map();
        let pose = m.start_pose;
        for yes in [
            "go to the red sofa, then loop back to me",
            "the fridge, then come back to the position you're in right now",
            "the fridge then return to your origin point",
            "the sofa, and after that head home",
            "then straight back to your first spot",
            "then back to square one",
            // What return_said reads, the map or not.
            "go to the sofa and come back here",
            "the sofa, and once ur done come over to me again",
            "the sofa, then finish next to me",
            "the fridge, then swing by me",
            "the fridge, and when that's done, come find me here",
        ] {
            assert!(return_said_on(&m, yes, pose, false), "{yes}");
        }
        for no in [
            "go back to the table you just visited",
            "come back to the kitchen",
            "return to the red sofa",
            "go back to the sofa that is red",
            "the chair at the back of the room",
            "back up 2 metres, then the sofa",
            "go back three metres",
            "go back to the one you saw",
            "go to the sofa",
            "tell me when you reach the sofa",
            "go to the sofa next to me",
            "come to me at the fridge",
        ] {
            assert!(!return_said_on(&m, no, pose, false), "{no}");
        }
        // In a conversation "back" may be to a place visited before.
        assert!(!return_said_on(&m, "now go back there", pose, true));
        assert!(return_said_on(&m, "now come back here", pose, true));
    }

    #[test]
    fn a_plan_that_never_comes_back_when_asked_to_is_found() {
        let asked = "go to the red sofa and then come back here";
        let come_back = |f: &[Finding]| f.iter().any(|x| x.to_model.contains("come back"));
        let f = findings(
            asked,
            "objects: [(sofa, None, red)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));",
        );
        assert!(come_back(&f), "{f:?}");
        assert!(f.iter().all(|x| x.kind == FindingKind::Word), "{f:?}");
        let f = findings(
            asked,
            "objects: [(sofa, None, red)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));\nmove_to_start();",
        );
        assert!(!come_back(&f), "{f:?}");
        // A position counts (a conversation's "where we started").
        let f = findings(
            asked,
            "objects: [(sofa, None, red)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));\nmove_to([1.0, 1.5]);",
        );
        assert!(!come_back(&f), "{f:?}");
        // Not asked: not found.
        let f = findings(
            "go to the red sofa",
            "objects: [(sofa, None, red)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));",
        );
        assert!(!come_back(&f), "{f:?}");
    }

    #[test]
    fn words_the_model_made_objects_of_are_not_requests() {
        let f = findings(
            "go to the grey sofa and back to where you started",
            "objects: [(grey, None, None), (sofa, None, red), (start, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));\nmove_to_start();",
        );
        // "grey" and "start" are not objects the person asked for; "grey" is a colour
        // the plan does not carry.
        assert!(
            f.iter().all(|x| x.kind != FindingKind::UnknownObject),
            "{f:?}"
        );
        assert!(
            f.iter()
                .any(|x| x.kind == FindingKind::Word && x.to_model.contains("grey")),
            "{f:?}"
        );
    }

    #[test]
    fn in_a_conversation_an_object_referred_back_to_is_reached_by_id_or_position() {
        let m = map();
        let a =
            parse_answer("objects: [(table, None, None)]\nplan:\nmove_to([4.0, 3.0]);").unwrap();
        let table = m.instances.iter().find(|i| i.label == "table").unwrap().id;
        let f = check_answer(
            &m,
            "go back to where we started",
            &a.tuples,
            &a.plan,
            m.start_pose,
            &[],
            &[table],
        );
        assert!(f.is_empty(), "{f:?}");
        // Outside a conversation the same answer leaves the table unused, where the
        // person named it.
        let f = check_answer(
            &m,
            "go back to the table",
            &a.tuples,
            &a.plan,
            m.start_pose,
            &[],
            &[],
        );
        assert!(
            f.iter()
                .any(|x| x.kind == FindingKind::Parts && x.to_model.contains("table")),
            "{f:?}"
        );
    }

    #[test]
    fn the_objects_line_is_judged_only_where_the_person_said_it() {
        // people.nav's pp-hc7 (dev): a right plan whose objects line carried a colour
        // and a room nobody said.
        let plan = "move_to_object(get_obj(\"table\", #{ordinal: 1, order: \"largest_to_smallest\"}));\nmove_to_object(get_obj(\"sink\"));\nmove_to_start();";
        let f = findings(
            "ok so first the biggest table, then the sink, and then back to where you started",
            &format!("objects: [(table, 1, purple), (sink, None, None), (living room, None, None)]\nplan:\n{plan}"),
        );
        assert!(f.is_empty(), "{f:?}");
        // Said, the same colour and room are findings; so is a synonym or a typo of a
        // name ("couch", "sofaa") the plan leaves out.
        for (instruction, tuple, kind) in [
            (
                "first the biggest purple table, then the sink, and then back to where you started",
                "(table, 1, purple)",
                FindingKind::NotOnMap,
            ),
            (
                "first the biggest table, then the sink, then the living room",
                "(living room, None, None)",
                FindingKind::Parts,
            ),
            (
                "first the biggest table, then the sink, then the couch",
                "(sofa, None, None)",
                FindingKind::Parts,
            ),
            (
                "first the biggest table, then the sink, then the sofaa",
                "(sofa, None, None)",
                FindingKind::Parts,
            ),
        ] {
            let f = findings(
                instruction,
                &format!("objects: [(table, 1, None), (sink, None, None), {tuple}]\nplan:\n{plan}"),
            );
            assert!(f.iter().any(|x| x.kind == kind), "{instruction}: {f:?}");
        }
        // A short word is read exactly: "to" is not a typo of "tv", nor "red" of "bed".
        let f = findings(
            "go to the red sofa",
            "objects: [(sofa, None, red), (tv, None, None), (bed, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));",
        );
        assert!(f.is_empty(), "{f:?}");
    }

    #[test]
    fn a_typo_names_the_object_it_is_closest_to() {
        let f = findings(
            "go to the tabel",
            "objects: [(tabel, None, None)]\nplan:\nmove_to_object(get_obj(\"table\"));",
        );
        assert!(f.is_empty(), "{f:?}");
    }

    #[test]
    fn grey_is_gray_and_cardinals_are_not_ordinals() {
        let f = findings(
            "stop between the two sofas, then go to the gray one",
            "objects: [(sofa, None, None), (sofa, None, grey)]\nplan:\nmove_between_the_two(\"sofa\");\nmove_to_object(get_obj(\"sofa\", #{colour: \"grey\"}));",
        );
        assert!(f.iter().all(|x| x.kind != FindingKind::Word), "{f:?}");
    }

    #[test]
    fn the_first_step_and_plain_counts_are_not_ordinals() {
        let f = findings(
            "first go to the sofa, then turn 90 degrees",
            "objects: [(sofa, None, None)]\nplan:\nmove_to_object(get_obj(\"sofa\"));\nturn(90);",
        );
        assert!(f.is_empty(), "{f:?}");
    }

    #[test]
    fn a_dropped_colour_is_asked_back_on_the_object_it_was_said_of() {
        let f = findings(
            "go to the second black chair counting from the north",
            "objects: [(chair, 2, black, north_to_south)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 2, order: \"north_to_south\"}));",
        );
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!(
            f[0].to_model,
            "the person said \"black chair\", but no chair in the plan has colour \"black\": write colour: \"black\" in that chair's selection"
        );
        assert_eq!(
            f[0].to_user,
            "which chair is black? there are 8 chairs (1 grey, 2 red, 3 black, 1 white, 1 blue)"
        );
    }

    #[test]
    fn a_dropped_colour_said_after_its_noun_is_asked_with_what_has_that_colour() {
        // "the chair that's red": no name follows the colour, nor comes right before
        // "the red one", so the question lists what on the map is red (flat-a: two red
        // chairs and the red sofa).
        let chair = "objects: [(chair, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\"));";
        for said in [
            "go to the chair that's red",
            "go to the chair, then the red one",
        ] {
            let f = findings(said, chair);
            assert_eq!(f.len(), 1, "{said}: {f:?}");
            assert_eq!(
                f[0].to_user,
                "what is red? I see 2 red chairs and 1 red sofa"
            );
            assert_eq!(f[0].bar, None);
        }
        let f = findings("go to the chair that's purple", chair);
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!(f[0].to_user, "what is purple? I see nothing purple");
    }

    #[test]
    fn a_colour_said_as_the_one_after_a_name_is_that_names() {
        // design.md: "the sofa, the red one" is a colour filter on the sofa.
        let m = map();
        assert_eq!(
            colour_nouns(
                &m,
                "go to the chair, the red one, then the tv",
                m.start_pose
            ),
            [("red".to_string(), "chair".to_string())]
        );
        // Not after another word, nor of what is excluded.
        for said in [
            "go to the chair, then the red one",
            "go to a chair other than the red one",
        ] {
            assert!(colour_nouns(&m, said, m.start_pose).is_empty(), "{said}");
        }
        // Dropped, the colour is asked of that name, and its re-ask must select on it.
        let f = findings(
            "go to the chair, the red one",
            "objects: [(chair, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\"));",
        );
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(
            f[0].to_user.starts_with("which chair is red? there are"),
            "{f:?}"
        );
        assert_eq!(
            f[0].bar,
            Some(Bar::ColourDropped {
                label: "chair".into()
            })
        );
        // Said only of the chair: another object's pick may not take it.
        let only = colour_said_only_of(&m, "the chair, the red one, then the sofa", m.start_pose);
        assert_eq!(only("red"), Some(vec!["chair".to_string()]));
    }

    #[test]
    fn a_colour_on_the_wrong_noun_is_found() {
        // flat-a has a black table and black chairs.
        let colour = "black";
        let instruction = format!("go to the chair next to the {colour} table");
        let wrong = findings(
            &instruction,
            &format!("objects: [(chair, None, None), (table, None, {colour})]\nplan:\nmove_to_object(get_obj(\"chair\", #{{colour: \"{colour}\", near: get_obj(\"table\")}}));"),
        );
        assert!(
            wrong.iter().any(|f| f.kind == FindingKind::Word
                && f.to_model.contains(&format!("\"{colour} table\""))),
            "{wrong:?}"
        );
        let right = findings(
            &instruction,
            &format!("objects: [(chair, None, None), (table, None, {colour})]\nplan:\nmove_to_object(get_obj(\"chair\", #{{near: get_obj(\"table\", #{{colour: \"{colour}\"}})}}));"),
        );
        assert!(right.is_empty(), "{right:?}");
        // A colour after its noun is not judged by position.
        let after = findings(
            &format!("go to the table, the {colour} one"),
            &format!("objects: [(table, None, {colour})]\nplan:\nmove_to_object(get_obj(\"table\", #{{colour: \"{colour}\"}}));"),
        );
        assert!(after.is_empty(), "{after:?}");
    }

    #[test]
    fn an_ordinal_on_the_wrong_noun_is_found() {
        let wrong = findings(
            "go to the chair next to the second table",
            "objects: [(chair, None, None), (table, 2, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 2, near: get_obj(\"table\")}));",
        );
        assert!(
            wrong
                .iter()
                .any(|f| f.to_model.contains("\"the second table\"")
                    && f.to_model.contains("no table")),
            "{wrong:?}"
        );
        // The question names the candidates.
        assert!(
            wrong.iter().any(|f| f
                .to_user
                .starts_with("which table is the second? there are 4 tables")),
            "{wrong:?}"
        );
        let right = findings(
            "go to the chair next to the second table",
            "objects: [(chair, None, None), (table, 2, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{near: get_obj(\"table\", #{ordinal: 2})}));",
        );
        assert!(right.is_empty(), "{right:?}");
    }

    #[test]
    fn chat_references_are_checked_against_the_visits() {
        let m = map();
        let refs = |instruction: &str, stops: &[u32], earlier: &[u32]| {
            check_visits(&m, instruction, m.start_pose, stops, earlier)
        };
        // "the other sofa" after sofa 2: going to 2 again is found, 1 is right
        let f = refs("now the other sofa", &[2], &[2]);
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(f[0].to_model.contains("not_visited: true"), "{f:?}");
        assert!(f[0].to_user.contains("sofa 2 (black)"), "{f:?}");
        assert!(refs("now the other sofa", &[1], &[2]).is_empty());
        assert!(refs("ok now the other one", &[1], &[2]).is_empty());
        assert_eq!(refs("ok now the other one", &[2], &[2]).len(), 1);
        // "the table you havent visited yet" after tables 8 and 3
        assert_eq!(
            refs("now the table you havent visited yet", &[8], &[8, 3]).len(),
            1
        );
        assert!(refs("now the table you havent visited yet", &[17], &[8, 3]).is_empty());
        // "back to the table you visited first" must go to a visited table
        let f = refs(
            "go to the tv and then back to the table you visited first",
            &[4, 17],
            &[8, 3],
        );
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(f[0].to_model.contains("visited: 1"), "{f:?}");
        assert!(refs(
            "go to the tv and then back to the table you visited first",
            &[4, 8],
            &[8, 3]
        )
        .is_empty());
        // "the same chair again", "the red one again", "that desk you were at"
        assert_eq!(refs("the same chair again", &[13], &[9]).len(), 1);
        assert!(refs("the same chair again", &[9], &[9]).is_empty());
        assert_eq!(refs("go back to the red one again", &[10], &[9]).len(), 1);
        assert!(refs("back to the desk you were at", &[25], &[25, 4]).is_empty());
        // mixed: the other fridge-like pick and the same table again, each on its own
        assert!(refs(
            "the other sofa, and after that the same table again",
            &[1, 8],
            &[2, 8]
        )
        .is_empty());
        // not references to a visited object: a room again, the other side, "went" alone
        assert!(refs("go to the kitchen again", &[24], &[22]).is_empty());
        assert!(refs("go to the other side of the table", &[8], &[8]).is_empty());
        assert!(refs("you went too far, go to the sofa", &[2], &[2]).is_empty());
        // outside a conversation, or without the dry run's stops, nothing is judged
        assert!(refs("the same chair again", &[13], &[]).is_empty());
        assert!(refs("the same chair again", &[], &[9]).is_empty());
    }

    #[test]
    fn directional_superlatives_and_size() {
        let ok = findings(
            "go to the westernmost chair and then the biggest sofa",
            "objects: [(chair, 1, None, west_to_east), (sofa, 1, None, largest_to_smallest)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 1, order: \"west_to_east\"}));\nmove_to_object(get_obj(\"sofa\", #{ordinal: 1, order: \"largest_to_smallest\"}));",
        );
        assert!(ok.is_empty(), "{ok:?}");
        let bad = findings(
            "go to the westernmost chair and then the biggest sofa",
            "objects: [(chair, None, None), (sofa, None, None)]\nplan:\nmove_to_object(get_obj(\"chair\"));\nmove_to_object(get_obj(\"sofa\"));",
        );
        assert_eq!(bad.len(), 2, "{bad:?}");
    }

    #[test]
    fn a_directional_superlative_is_the_first_from_its_side_on_its_noun() {
        let said = "go to the westernmost chair";
        // The first west-first or the last east-first; an order alone is the first.
        for ok in [
            "#{ordinal: 1, order: \"west_to_east\"}",
            "#{order: \"west_to_east\"}",
            "#{ordinal: -1, order: \"east_to_west\"}",
        ] {
            let f = findings_for_pick(said, "chair", ok);
            assert!(f.is_empty(), "{ok}: {f:?}");
        }
        // Held-out v4 (dev): the easternmost, and the second from the west.
        for (bad, says) in [
            ("#{ordinal: -1, order: \"west_to_east\"}", "counts order \"west_to_east\" from the other end: for the westernmost write ordinal: 1 with order \"west_to_east\""),
            ("#{ordinal: 2, order: \"west_to_east\"}", "for the westernmost write ordinal: 1"),
            ("#{ordinal: 1, order: \"east_to_west\"}", "for the westernmost write ordinal: 1"),
        ] {
            assert_word_finding(said, "chair", bad, says);
        }
        // Another object's first from the west does not stand for the chair's.
        let f = findings(
            "go to the westernmost chair, then the table",
            "objects: [(chair, None, None), (table, 1, None, west_to_east)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 2, order: \"west_to_east\"}));\nmove_to_object(get_obj(\"table\", #{ordinal: 1, order: \"west_to_east\"}));",
        );
        assert!(
            f.iter().any(|x| x.to_model.contains("for the westernmost")),
            "{f:?}"
        );
        // "The second westernmost" is the second from the west.
        let said = "go to the second westernmost chair";
        for ok in [
            "#{ordinal: 2, order: \"west_to_east\"}",
            "#{ordinal: -2, order: \"east_to_west\"}",
        ] {
            let f = findings_for_pick(said, "chair", ok);
            assert!(f.is_empty(), "{ok}: {f:?}");
        }
        assert_word_finding(
            said,
            "chair",
            "#{ordinal: 1, order: \"west_to_east\"}",
            "that is ordinal: 2 with order \"west_to_east\"",
        );
        // After "from" it is the end a count starts at (held-out v14, dev, pb04).
        let said = "go to the second chair counting from the westernmost one";
        let f = findings_for_pick(said, "chair", "#{ordinal: 2, order: \"west_to_east\"}");
        assert!(f.is_empty(), "{f:?}");
        assert_word_finding(
            said,
            "chair",
            "#{ordinal: 2, order: \"east_to_west\"}",
            "counts from the westernmost end",
        );
    }
}
