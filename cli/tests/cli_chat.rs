//! `ivlmap chat` with stdin not a terminal: commands work line by line, and
//! instructions go through the backend (here a replay cassette that does not hold
//! them, so the error is reported and the chat goes on).

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

mod support;
use support::chat;

#[test]
fn piped_commands_run_without_a_terminal() {
    let d = tempfile::tempdir().unwrap();
    let png = d.path().join("c.png");
    let input = format!(
        ":help\n:where\n:undo\n:render {}\n:frob\n:quit\n:where\n",
        png.display()
    );
    let (code, out, err) = chat(&input, &[]);
    assert_eq!(code, Some(0), "{err}");
    assert!(out.contains(":preview"), "{out}");
    assert!(
        out.contains("at (4.00, 3.00)") && out.contains("living room"),
        "{out}"
    );
    assert!(out.contains("nothing to undo"), "{out}");
    assert!(out.contains("unknown command :frob"), "{out}");
    // :quit stops reading: the second :where is never answered.
    assert_eq!(out.matches("heading").count(), 1, "{out}");
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
}

#[test]
fn a_backend_error_is_reported_and_the_chat_goes_on() {
    let d = tempfile::tempdir().unwrap();
    let cassette = d.path().join("empty.jsonl");
    std::fs::write(&cassette, "").unwrap();
    let (code, out, err) = chat(
        "go to the red sofa\n:where\n",
        &[
            "--backend",
            "replay",
            "--cassette",
            cassette.to_str().unwrap(),
        ],
    );
    assert_eq!(code, Some(0), "{err}");
    assert!(out.contains("error:") && out.contains("cassette"), "{out}");
    assert!(out.contains("at (4.00, 3.00)"), "{out}");
}
