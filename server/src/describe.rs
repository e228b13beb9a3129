//! Words for one instance that pick it out on its map ("the second yellow table from the
//! west"), checked with the map's own query: the page puts them into the input when a
//! person clicks an object.

use map_core::matcher::LexicalMatcher;
use map_core::select::Selection;
use map_core::{Instance, IvlMap, ObjectOrder};

/// "first" .. "tenth", then "11th", "12th", ...
#[must_use]
pub fn ordinal_words(k: usize) -> String {
    const WORDS: [&str; 10] = [
        "first", "second", "third", "fourth", "fifth", "sixth", "seventh", "eighth", "ninth",
        "tenth",
    ];
    match k.checked_sub(1).and_then(|i| WORDS.get(i)) {
        Some(w) => (*w).to_string(),
        None => map_core::query::ordinal_word(i64::try_from(k).unwrap_or(i64::MAX)),
    }
}

/// How `inst` is told apart from the others of its label: "the sofa" when it is the only
/// sofa, "the red chair" when its colour is enough, else its rank among the same label
/// and colour counted from the west ("the second yellow table from the west"). Every
/// form except the plain one is checked with [`IvlMap::select`], so the words lead back
/// to `inst`; `None` for an id the map lacks or words that would not.
#[must_use]
pub fn describe(map: &IvlMap, id: u32) -> Option<String> {
    let inst = map.instance_by_id(id)?;
    let same: Vec<&Instance> = map
        .instances
        .iter()
        .filter(|i| i.label == inst.label)
        .collect();
    if same.len() == 1 {
        return Some(format!("the {}", inst.label));
    }
    let colour = inst.colour.as_deref().filter(|c| !c.trim().is_empty());
    let noun = match colour {
        Some(c) => format!("{c} {}", inst.label),
        None => inst.label.clone(),
    };
    let mut sel = Selection::new(inst.label.clone());
    if let Some(c) = colour {
        sel = sel.colour(c);
    }
    let sel = sel.ordered(ObjectOrder::WestToEast.name()).ok()?;
    let (_, ranked) = map
        .candidates_with(&LexicalMatcher, &sel, map.start_pose)
        .ok()?;
    if colour.is_some() && ranked.len() == 1 && ranked[0].id == id {
        return Some(format!("the {noun}"));
    }
    let k = ranked.iter().position(|i| i.id == id)? + 1;
    let picked = map
        .select(&sel.nth(i64::try_from(k).ok()?), map.start_pose)
        .ok()?;
    (picked.id == id).then(|| format!("the {} {noun} from the west", ordinal_words(k)))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use map_core::Scene;

    fn flat_a() -> IvlMap {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/scenes/flat-a.scene.json"
        );
        IvlMap::from_scene(&Scene::from_path(path).unwrap())
    }

    #[test]
    fn words_pick_out_each_instance() {
        let map = flat_a();
        // flat-a: yellow tables 8 (x 8.6) and 17 (x 10.0); one fridge; red chairs 9, 10.
        assert_eq!(
            describe(&map, 17).as_deref(),
            Some("the second yellow table from the west")
        );
        assert_eq!(
            describe(&map, 8).as_deref(),
            Some("the first yellow table from the west")
        );
        assert_eq!(describe(&map, 16).as_deref(), Some("the fridge"));
        assert_eq!(describe(&map, 1).as_deref(), Some("the red sofa"));
        assert_eq!(describe(&map, 999), None);
        for i in &map.instances {
            assert!(describe(&map, i.id).is_some(), "{}", i.id);
        }
        assert_eq!(ordinal_words(2), "second");
        assert_eq!(ordinal_words(12), "12th");
    }
}
