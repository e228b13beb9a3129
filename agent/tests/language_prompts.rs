//! Prompt files: the repository's folder, variant overlays, errors that name the file.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use agent::prompts::TEMPLATE_NAMES;
use agent::{PromptError, Prompts};

fn repo_prompts() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../prompts")
}

#[test]
fn repository_folder_is_the_builtin_set() {
    let disk = Prompts::load(repo_prompts()).unwrap();
    let builtin = Prompts::builtin();
    for n in TEMPLATE_NAMES {
        assert_eq!(disk.source(n), builtin.source(n), "{n}");
    }
    // The step functions come from planner_dsl's registry, every one of them.
    let sys = builtin.v2_system(None).unwrap();
    for name in planner_dsl::typed::STEP_FUNCTIONS {
        let f = planner_dsl::lookup(name).unwrap();
        assert!(sys.contains(&f.signature()), "{}", f.name);
    }
}

#[test]
fn variant_overrides_only_its_files() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("v2_reask.md.j2"),
        "Mind: {% for f in findings %}{{ f | upper }}{% endfor %}\n",
    )
    .unwrap();
    let p = Prompts::load_variant(repo_prompts(), dir.path()).unwrap();
    let m = p.v2_reask(&["no table".into()]).unwrap();
    assert_eq!(m.content, "Mind: NO TABLE");
    assert_eq!(
        p.source("v2_system.md.j2"),
        Prompts::builtin().source("v2_system.md.j2")
    );
    assert!(p
        .origin("v2_reask.md.j2")
        .unwrap()
        .ends_with("v2_reask.md.j2"));
    assert!(p
        .origin("v2_system.md.j2")
        .unwrap()
        .contains("v2_system.md.j2"));
}

#[test]
fn shared_prefix_is_identical_across_instructions() {
    let p = Prompts::builtin();
    let scene = "objects: bed (1 white)";
    let a = p.v2_system(Some(scene)).unwrap();
    let b = p.v2_system(Some(scene)).unwrap();
    assert_eq!(a, b);
    // What varies is in the request only.
    let r1 = p.v2_request("go to the bed", None, Some(scene)).unwrap();
    let r2 = p
        .v2_request("face north", Some("visited so far: bed 3"), Some(scene))
        .unwrap();
    assert!(r1.content.ends_with("> go to the bed"), "{}", r1.content);
    assert!(
        r2.content
            .contains("Earlier in this conversation: visited so far: bed 3"),
        "{}",
        r2.content
    );
    assert!(!a.contains("go to the bed") && !a.contains("face north"));
}

#[test]
fn broken_variants_fail_at_load_with_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("v2_system.md.j2"), "fine\n{% if %}\n").unwrap();
    let e = Prompts::load(dir.path()).unwrap_err();
    let PromptError::Template { origin, line, .. } = &e else {
        panic!("{e}")
    };
    assert!(origin.ends_with("v2_system.md.j2"), "{e}");
    assert_eq!(*line, Some(2), "{e}");

    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("v2_sytem.md.j2"), "typo\n").unwrap();
    assert!(matches!(
        Prompts::load(dir.path()),
        Err(PromptError::UnknownFile { .. })
    ));

    // A variable that does not exist is an error when rendered, not silent emptiness.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("v2_request.md.j2"), "{{ instrction }}\n").unwrap();
    let p = Prompts::load(dir.path()).unwrap();
    assert!(p.v2_request("x", None, None).is_err());

    assert!(matches!(
        Prompts::load("/nonexistent/prompts"),
        Err(PromptError::Io { .. })
    ));
}

#[test]
fn the_quoted_variant_is_the_default_examples_with_the_words_quoted() {
    // prompts/variants/quoted copies the default worked examples and adds a comment line
    // above each call: the copies must not drift apart, or comparing the two measures
    // more than the answer form.
    let examples = |p: &Prompts| {
        let (text, origin) = p.worked_examples();
        agent::v2::examples::parse_examples(text, origin).unwrap()
    };
    let default = examples(&Prompts::builtin());
    let quoted = examples(&Prompts::load(repo_prompts().join("variants/quoted")).unwrap());
    assert_eq!(default.len(), quoted.len());
    for (d, q) in default.iter().zip(&quoted) {
        assert_eq!(d.instruction, q.instruction, "line {}", q.line);
        assert_eq!(d.history, q.history, "line {}", q.line);
        let unquoted: Vec<&str> = q.answer.lines().filter(|l| !l.starts_with("// ")).collect();
        let plain: Vec<&str> = d.answer.lines().collect();
        assert_eq!(plain, unquoted, "line {}", q.line);
        assert!(
            q.answer.lines().any(|l| l.starts_with("// ")),
            "line {}",
            q.line
        );
    }
}
