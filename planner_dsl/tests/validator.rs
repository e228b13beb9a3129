//! Compile-time checks: every violation reported at once, at its exact position.

#![allow(clippy::panic)] // test helpers

use planner_dsl::{Plan, PlanError, Span, ViolationKind};

fn violations(src: &str) -> Vec<(usize, usize, ViolationKind)> {
    match Plan::compile(src) {
        Err(PlanError::Rejected { violations }) => violations
            .into_iter()
            .map(|v| (v.span.line, v.span.col, v.kind))
            .collect(),
        other => panic!("expected a rejection, got {other:?}"),
    }
}

#[test]
fn agent_methods_and_plain_calls_are_the_same_library() {
    let plan = Plan::compile(
        "let t = agent.get_obj_attributes(\"table\", 3, \"yellow\");\nface(t);\nagent.move_to_object(t);\nmove_forward(1.5);",
    )
    .unwrap();
    let calls: Vec<(&str, usize, usize)> = plan
        .library_calls()
        .iter()
        .map(|c| (c.function.as_str(), c.span.line, c.span.col))
        .collect();
    assert_eq!(
        calls,
        [
            ("get_obj_attributes", 1, 15),
            ("face", 2, 1),
            ("move_to_object", 3, 7),
            ("move_forward", 4, 1)
        ]
    );
}

#[test]
fn all_violations_at_once_with_positions() {
    let src = "agent.fly(1);\nlet x = sleep(2);\n  print(x);\nagent.turn(1, 2);\nlet c = [1].map(|v| v);\nx.move_to([0, 0]);";
    let v = violations(src);
    let at: Vec<(usize, usize)> = v.iter().map(|(l, c, _)| (*l, *c)).collect();
    assert_eq!(
        at,
        [(1, 7), (2, 9), (3, 3), (4, 7), (5, 13), (5, 17), (6, 3)],
        "{v:?}"
    );
    assert!(matches!(&v[0].2, ViolationKind::BadMethod { name, .. } if name == "fly"));
    assert!(matches!(&v[1].2, ViolationKind::Forbidden { name, .. } if name == "sleep"));
    assert!(matches!(&v[2].2, ViolationKind::Forbidden { reason, .. } if reason.contains("say(")));
    assert!(
        matches!(&v[3].2, ViolationKind::WrongArity { name, got: 2, expected, .. } if name == "turn" && expected == "1 argument")
    );
    assert!(matches!(&v[4].2, ViolationKind::BadMethod { name, .. } if name == "map"));
    assert_eq!(v[5].2, ViolationKind::Closure);
    assert!(
        matches!(&v[6].2, ViolationKind::BadMethod { hint: Some(h), .. } if h.contains("agent.move_to("))
    );
}

#[test]
fn misspelt_library_function_gets_a_suggestion() {
    let v = violations("agent.move_to_objct(\"sofa\");\nget_obj_atributes(\"sofa\");");
    assert_eq!(v.len(), 2);
    assert!(
        matches!(&v[0].2, ViolationKind::BadMethod { hint: Some(h), .. } if h.contains("`move_to_object`")),
        "{v:?}"
    );
    assert!(
        matches!(&v[1].2, ViolationKind::UnknownFunction { hint: Some(h), .. } if h.contains("`get_obj_attributes`")),
        "{v:?}"
    );
}

#[test]
fn disabled_keywords_fail_to_parse_with_position() {
    for (src, line, col) in [
        ("let a = 1;\neval(\"a\")", 2, 1),
        ("let f = Fn(\"turn\");", 1, 9),
        ("  import \"x\" as y;", 1, 3),
    ] {
        match Plan::compile(src) {
            Err(PlanError::Syntax { span, message }) => {
                assert_eq!(span, Span { line, col }, "{src}: {message}");
                assert!(message.contains("disabled"), "{message}");
            }
            other => panic!("{src}: {other:?}"),
        }
    }
}

#[test]
fn script_functions_builtins_and_control_flow_are_allowed() {
    let src = r#"
fn visit(names) {
    for n in names {
        if n.len() > 0 { agent.move_to_object(n); }
    }
    names.len()
}
let xs = ["sofa", "tv"];
xs.push("table");
let count = visit(xs);
let m = #{a: 1, b: [1.5, 2]};
m.c = abs(-2) + sqrt(4.0) + max(1, 2);
let s = `${count} ${m.keys().len()} ${"x".to_upper()}`;
let i = 0;
while i < 3 { i += 1; if i == 2 { continue; } }
switch count { 3 => say(s), _ => say("?") }
"#;
    let plan = Plan::compile(src).unwrap();
    let names: Vec<&str> = plan
        .library_calls()
        .iter()
        .map(|c| c.function.as_str())
        .collect();
    assert_eq!(names, ["move_to_object", "say", "say"]);
}

#[test]
fn reserved_names_and_index_assignment() {
    let v = violations(
        "fn face(o) { }\nlet agent = 2;\nlet m = #{};\nm[\"k\"] = 1;\nfor agent in [1] { }",
    );
    let at: Vec<(usize, usize)> = v.iter().map(|(l, c, _)| (*l, *c)).collect();
    assert_eq!(at, [(1, 1), (2, 5), (4, 1), (5, 5)], "{v:?}");
    assert!(matches!(&v[0].2, ViolationKind::Reserved { name, .. } if name == "face"));
    assert!(matches!(&v[1].2, ViolationKind::Reserved { name, .. } if name == "agent"));
    assert_eq!(v[2].2, ViolationKind::IndexAssignment);
}

#[test]
fn plan_error_display_lists_every_problem() {
    let e = Plan::compile("agent.fly();\nsleep(1);").unwrap_err();
    let text = e.to_string();
    assert!(text.starts_with("plan rejected (2 problems):"), "{text}");
    assert!(text.contains("line 1, column 7"), "{text}");
    assert!(text.contains("line 2, column 1"), "{text}");
    let json = serde_json::to_value(&e).unwrap();
    assert_eq!(json["kind"], "rejected");
    assert_eq!(json["violations"][1]["span"]["line"], 2);
}

#[test]
fn undefined_variables_are_caught_before_running() {
    match Plan::compile("let t = agent.get_obj_attributes(\"table\");\nagent.face(obj_attr);") {
        Err(PlanError::Syntax { span, message }) => {
            assert_eq!(span, Span { line: 2, col: 12 });
            assert_eq!(message, "Undefined variable: obj_attr");
        }
        other => panic!("{other:?}"),
    }
    // `agent` is known everywhere, also inside script functions.
    Plan::compile("fn f(o) { agent.face(o); }\nf(\"tv\");").unwrap();
}
