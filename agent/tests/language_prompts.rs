//! Prompt files: the repository's folder, variant overlays, errors that name the file.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use agent::prompts::TEMPLATE_NAMES;
use agent::{PromptError, Prompts, Tuple};

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
    // The function list comes from planner_dsl's registry, every function of it.
    let sys = builtin.plan_system().unwrap();
    assert!(sys.contains(planner_dsl::function_list_for_prompt().trim_end()));
    for f in planner_dsl::registry() {
        assert!(
            sys.contains(&format!("agent.{}", f.signature())),
            "{}",
            f.name
        );
    }
}

#[test]
fn variant_overrides_only_its_files() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("codegen.md.j2"),
        "Only ever answer with a ```rhai block. {{ 'VARIANT' | lower }}\n",
    )
    .unwrap();
    let p = Prompts::load_variant(repo_prompts(), dir.path()).unwrap();
    let sys = p.plan_system().unwrap();
    assert!(
        sys.contains("Only ever answer with a ```rhai block. variant"),
        "{sys}"
    );
    assert!(sys.contains("agent.get_obj_attributes("), "functions kept");
    assert_eq!(
        p.source("attributes.md.j2"),
        Prompts::builtin().source("attributes.md.j2")
    );
    assert!(p
        .origin("codegen.md.j2")
        .unwrap()
        .ends_with("codegen.md.j2"));
    assert!(p.origin("system.md.j2").unwrap().contains("system.md.j2"));
}

#[test]
fn shared_prefix_is_identical_across_instructions() {
    let p = Prompts::builtin();
    let a = p
        .plan_messages(
            "go to the bed",
            &[Tuple::new("bed", None, None)],
            Some("objects: 1 bed (1 white)"),
            None,
        )
        .unwrap();
    let b = p
        .plan_messages(
            "go to the tv",
            &[Tuple::new("tv", None, None)],
            Some("objects: 1 bed (1 white)"),
            Some("\"x\" -> stopped at bed"),
        )
        .unwrap();
    assert_eq!(a[0], b[0]);
    assert!(
        a[1].content.ends_with("Objects: [(bed, None, None)]"),
        "{}",
        a[1].content
    );
    assert!(
        b[1].content.contains("Earlier in this conversation: \"x\""),
        "{}",
        b[1].content
    );
    let e1 = p.extract_messages("go to the bed", None).unwrap();
    let e2 = p.extract_messages("face north", None).unwrap();
    assert_eq!(e1[0], e2[0]);
    assert_eq!(e2[1].content, "I: face north");
}

#[test]
fn broken_variants_fail_at_load_with_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("examples.md.j2"), "fine\n{% if %}\n").unwrap();
    let e = Prompts::load(dir.path()).unwrap_err();
    let PromptError::Template { origin, line, .. } = &e else {
        panic!("{e}")
    };
    assert!(origin.ends_with("examples.md.j2"), "{e}");
    assert_eq!(*line, Some(2), "{e}");

    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("codgen.md.j2"), "typo\n").unwrap();
    assert!(matches!(
        Prompts::load(dir.path()),
        Err(PromptError::UnknownFile { .. })
    ));

    // A variable that does not exist is an error when rendered, not silent emptiness.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("plan_request.md.j2"), "{{ instrction }}\n").unwrap();
    let p = Prompts::load(dir.path()).unwrap();
    assert!(p.plan_messages("x", &[], None, None).is_err());

    assert!(matches!(
        Prompts::load("/nonexistent/prompts"),
        Err(PromptError::Io { .. })
    ));
}
