//! README.md's function table is generated from the registry and must not drift.

#[test]
fn readme_function_table_matches_the_registry() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md");
    let text = std::fs::read_to_string(&path).unwrap();
    let (begin, end) = ("<!-- registry:begin -->\n", "<!-- registry:end -->");
    let a = text.find(begin).unwrap() + begin.len();
    let b = text.find(end).unwrap();
    let want = planner_dsl::registry_markdown();
    if std::env::var_os("UPDATE_README").is_some() {
        let new = format!("{}{}{}", &text[..a], want, &text[b..]);
        std::fs::write(&path, new).unwrap();
        return;
    }
    assert_eq!(
        &text[a..b],
        want,
        "README.md is stale: run UPDATE_README=1 cargo test -p planner_dsl --test readme"
    );
}

#[test]
fn readme_limits_table_matches_the_defaults() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md");
    let text = std::fs::read_to_string(path).unwrap();
    let l = planner_dsl::Limits::default();
    let thousands = |n: u64| {
        let s = n.to_string();
        let mut out = String::new();
        for (i, c) in s.chars().enumerate() {
            if i > 0 && (s.len() - i).is_multiple_of(3) {
                out.push(',');
            }
            out.push(c);
        }
        out
    };
    for row in [
        format!("| operations | {} |", thousands(l.max_operations)),
        format!("| call levels (recursion) | {} |", l.max_call_levels),
        format!(
            "| expression depth (top level / in functions) | {} / {} |",
            l.max_expr_depth, l.max_function_expr_depth
        ),
        format!("| string size | {} KiB |", l.max_string_size / 1024),
        format!("| array size | {} |", thousands(l.max_array_size as u64)),
        format!("| map size | {} |", thousands(l.max_map_size as u64)),
        format!("| variables | {} |", l.max_variables),
        format!("| script functions | {} |", l.max_functions),
        format!("| library calls per run | {} |", l.max_library_calls),
        format!("| script size | {} KiB |", l.max_source_bytes / 1024),
        format!(
            "| wall-clock deadline (script time, not counting library calls) | {} ms |",
            l.deadline.as_millis()
        ),
    ] {
        assert!(text.contains(&row), "README lacks {row}");
    }
}
