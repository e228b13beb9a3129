//! A GBNF grammar of plan scripts, generated from the registry.
//!
//! Given to llama.cpp's grammar sampler, it makes a local model unable to write a call
//! outside the function library: every call is `agent.f(...)` or `f(...)` with `f` one
//! of the registry's names, arguments are literals, variables or further library calls,
//! and statements are `let`, calls, `for` loops over ranges and `//` comments. The
//! grammar is a subset of what [`crate::Plan::compile`] accepts, so a script it admits
//! still goes through the validator (arity, argument types, limits).

use crate::registry::registry;

/// GBNF for one fenced plan: "```rhai\n" lines "```". The rule `root` is the start.
///
/// ```
/// let g = planner_dsl::script_grammar();
/// assert!(g.starts_with("root ::="));
/// assert!(g.contains("\"move_to_object\""));
/// assert!(!g.contains("\"eval\""));
/// ```
#[must_use]
pub fn script_grammar() -> String {
    let mut names: Vec<&str> = registry().iter().map(|f| f.name).collect();
    // Longer names first so that no name is cut short by a prefix of it.
    names.sort_by_key(|n| std::cmp::Reverse(n.len()));
    let fname = names
        .iter()
        .map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(" | ");
    format!(
        r#"root ::= "```rhai\n" line+ "```"
line ::= indent? (stmt | comment) "\n"
indent ::= "    " | "  " | "        "
stmt ::= letstmt | callstmt | forstmt
letstmt ::= "let " ident " = " expr ";"
callstmt ::= call ";"
forstmt ::= "for " ident " in " int ".." int " {{\n" line+ indent? "}}"
comment ::= "// " [^\n]*
call ::= "agent."? fname "(" args? ")"
fname ::= {fname}
args ::= expr (", " expr)*
expr ::= call | string | number | ident | "()"
string ::= "\"" [^"\\\n]{{0,60}} "\""
number ::= "-"? int ("." [0-9]{{1,3}})?
int ::= [0-9]{{1,4}}
ident ::= [a-z_] [a-z0-9_]{{0,24}}
"#
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_library_function_is_callable_and_nothing_else() {
        let g = script_grammar();
        for f in registry() {
            assert!(g.contains(&format!("\"{}\"", f.name)), "{}", f.name);
        }
        for forbidden in ["\"eval\"", "\"import\"", "\"Fn\"", "\"print\""] {
            assert!(!g.contains(forbidden), "{forbidden}");
        }
        // Rules are all defined.
        for rule in [
            "root", "line", "stmt", "call", "fname", "expr", "ident", "string",
        ] {
            assert!(g.contains(&format!("\n{rule} ::=")) || g.starts_with(&format!("{rule} ::=")));
        }
    }
}
