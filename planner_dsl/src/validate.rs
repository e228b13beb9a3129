//! The validator: walks the compiled AST and checks every call against the
//! allow-lists. All violations are collected, each with its line and column.

use crate::error::{Span, Violation, ViolationKind};
use crate::registry::{lookup, registry, BUILTIN_ALLOW_LIST, FORBIDDEN};
use rhai::{ASTNode, Expr, FnCallExpr, Stmt, AST};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// A call of a library function found in a plan, in source order.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CallSite {
    /// Library function name.
    pub function: String,
    /// Where it is called.
    pub span: Span,
    /// Number of arguments written.
    pub args: usize,
}

/// Operators that the parser may emit as plain function calls.
const OPERATORS: &[&str] = &[
    "+", "-", "*", "/", "%", "**", "==", "!=", "<", "<=", ">", ">=", "!", "&", "|", "^", "<<",
    ">>", "..", "..=", "contains",
];

struct Walker<'s> {
    script_fns: HashMap<&'s str, Vec<usize>>,
    violations: Vec<Violation>,
    calls: Vec<CallSite>,
}

fn forbidden(name: &str) -> Option<&'static str> {
    FORBIDDEN.iter().find(|(n, _)| *n == name).map(|(_, r)| *r)
}

fn suggestion(name: &str) -> Option<String> {
    let lib = registry().iter().map(|f| f.name);
    let best = lib
        .chain(BUILTIN_ALLOW_LIST.iter().copied())
        .map(|c| (strsim::levenshtein(name, c), c))
        .min_by_key(|(d, _)| *d)?;
    let len = name.chars().count();
    let limit = (len / 3).clamp(1, 4);
    (len >= 4 && best.0 <= limit).then(|| format!("did you mean `{}`?", best.1))
}

fn unknown_hint(name: &str) -> Option<String> {
    suggestion(name).or_else(|| {
        Some("plans may call only the robot function library, say(), and basic maths, string, array and map functions".into())
    })
}

impl Walker<'_> {
    fn push(&mut self, pos: rhai::Position, kind: ViolationKind) {
        self.violations.push(Violation {
            span: Span::from_position(pos),
            kind,
        });
    }

    /// Report `name` if it is on the forbidden list (eval, sleep, print...); true if it was.
    fn push_if_forbidden(&mut self, pos: rhai::Position, name: &str) -> bool {
        let Some(reason) = forbidden(name) else {
            return false;
        };
        self.push(
            pos,
            ViolationKind::Forbidden {
                name: name.to_string(),
                reason: reason.to_string(),
            },
        );
        true
    }

    fn library_call(&mut self, x: &FnCallExpr, pos: rhai::Position) -> bool {
        let Some(spec) = lookup(x.name.as_str()) else {
            return false;
        };
        let got = x.args.len();
        if spec.accepts_arity(got) {
            self.calls.push(CallSite {
                function: spec.name.to_string(),
                span: Span::from_position(pos),
                args: got,
            });
        } else {
            self.push(
                pos,
                ViolationKind::WrongArity {
                    name: spec.name.to_string(),
                    expected: spec.arity_text(),
                    got,
                    signature: spec.signature(),
                },
            );
        }
        true
    }

    fn script_fn_arity_ok(&self, name: &str, n: usize) -> Option<bool> {
        self.script_fns.get(name).map(|ar| ar.contains(&n))
    }

    fn plain_call(&mut self, x: &FnCallExpr, pos: rhai::Position) {
        let name = x.name.as_str();
        if x.op_token.is_some() || OPERATORS.contains(&name) {
            return;
        }
        match self.script_fn_arity_ok(name, x.args.len()) {
            Some(true) => return,
            Some(false) => {
                self.push(
                    pos,
                    ViolationKind::UnknownFunction {
                        name: name.to_string(),
                        hint: Some(format!(
                            "the script defines `{name}` but not with {} parameters",
                            x.args.len()
                        )),
                    },
                );
                return;
            }
            None => {}
        }
        if self.library_call(x, pos) || BUILTIN_ALLOW_LIST.contains(&name) {
            return;
        }
        if name == "curry" && x.args.first().is_some_and(is_fn_ptr) {
            // A capturing closure; reported once, at the closure.
            return;
        }
        if self.push_if_forbidden(pos, name) {
            return;
        }
        self.push(
            pos,
            ViolationKind::UnknownFunction {
                name: name.to_string(),
                hint: unknown_hint(name),
            },
        );
    }

    fn method_call(&mut self, x: &FnCallExpr, pos: rhai::Position, on_agent: bool) {
        let name = x.name.as_str();
        if on_agent {
            if self.library_call(x, pos) {
                return;
            }
            let hint = suggestion(name)
                .filter(|s| {
                    registry()
                        .iter()
                        .any(|f| s.contains(&format!("`{}`", f.name)))
                })
                .unwrap_or_else(|| "agent offers only the robot function library".to_string());
            self.push(
                pos,
                ViolationKind::BadMethod {
                    name: name.to_string(),
                    hint: Some(hint),
                },
            );
            return;
        }
        if self.script_fn_arity_ok(name, x.args.len()) == Some(true)
            || BUILTIN_ALLOW_LIST.contains(&name)
        {
            return;
        }
        if lookup(name).is_some() {
            self.push(
                pos,
                ViolationKind::BadMethod {
                    name: name.to_string(),
                    hint: Some(format!(
                        "call library functions as agent.{name}(...) or {name}(...)"
                    )),
                },
            );
            return;
        }
        if self.push_if_forbidden(pos, name) {
            return;
        }
        self.push(
            pos,
            ViolationKind::BadMethod {
                name: name.to_string(),
                hint: unknown_hint(name),
            },
        );
    }

    fn reserved_var(&mut self, name: &str, pos: rhai::Position) {
        if name == "agent" {
            self.push(
                pos,
                ViolationKind::Reserved {
                    name: name.to_string(),
                    reason: "`agent` is the robot; choose another variable name".into(),
                },
            );
        }
    }

    fn visit(&mut self, path: &[ASTNode<'_>]) {
        let Some(node) = path.last() else { return };
        match node {
            ASTNode::Stmt(Stmt::FnCall(x, pos)) => self.plain_call(x, *pos),
            ASTNode::Stmt(Stmt::Var(x, ..)) => self.reserved_var(x.0.name.as_str(), x.0.pos),
            ASTNode::Stmt(Stmt::For(x, _)) => {
                self.reserved_var(x.0.name.as_str(), x.0.pos);
                if let Some(counter) = &x.1 {
                    self.reserved_var(counter.name.as_str(), counter.pos);
                }
            }
            ASTNode::Stmt(Stmt::Assignment(x)) if has_index(&x.1.lhs) => {
                self.push(x.1.lhs.start_position(), ViolationKind::IndexAssignment);
            }
            ASTNode::Stmt(Stmt::Assignment(x)) if is_agent(&x.1.lhs) => {
                self.reserved_var("agent", x.1.lhs.start_position());
            }
            ASTNode::Expr(Expr::FnCall(x, pos)) => self.plain_call(x, *pos),
            ASTNode::Expr(Expr::MethodCall(x, pos)) => {
                let on_agent = receiver(path).is_some_and(is_agent);
                self.method_call(x, *pos, on_agent);
            }
            ASTNode::Expr(e @ Expr::DynamicConstant(..)) if is_fn_ptr(e) => {
                self.push(e.position(), ViolationKind::Closure);
            }
            _ => {}
        }
    }
}

/// Whether an assignment target writes through an index (`a[i]`, `m.a[k]`).
fn has_index(e: &Expr) -> bool {
    match e {
        Expr::Index(..) => true,
        Expr::Dot(bin, ..) => has_index(&bin.lhs) || has_index(&bin.rhs),
        _ => false,
    }
}

fn is_fn_ptr(e: &Expr) -> bool {
    matches!(e, Expr::DynamicConstant(d, _) if d.is_fnptr())
}

fn is_agent(e: &Expr) -> bool {
    matches!(e, Expr::Variable(v, ..) if v.1.as_str() == "agent")
}

/// The expression a method call at the end of `path` is called on.
///
/// Rhai nests chains to the right: `a.f().g` is `Dot(a, Dot(f(), g))` and
/// `a.f()[0]` is `Dot(a, Index(f(), 0))`, so walk up while the node is the left side
/// of a `Dot` or `Index` until it is the right side of a `Dot`.
fn receiver<'a>(path: &[ASTNode<'a>]) -> Option<&'a Expr> {
    let mut i = path.len().checked_sub(1)?;
    loop {
        let ASTNode::Expr(child) = path[i] else {
            return None;
        };
        let ASTNode::Expr(parent) = path.get(i.checked_sub(1)?)? else {
            return None;
        };
        match parent {
            Expr::Dot(bin, ..) if std::ptr::eq(&bin.rhs, child) => return Some(&bin.lhs),
            Expr::Dot(bin, ..) | Expr::Index(bin, ..) if std::ptr::eq(&bin.lhs, child) => {
                i -= 1;
            }
            _ => return None,
        }
    }
}

/// Where `fn name` is written (the AST keeps no position for function definitions).
fn fn_def_span(source: &str, name: &str) -> Span {
    for (i, line) in source.lines().enumerate() {
        let mut from = 0;
        while let Some(k) = line[from..].find("fn ") {
            let at = from + k;
            let rest = line[at + 3..].trim_start();
            let before_ok =
                at == 0 || !line[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_');
            if before_ok
                && rest.starts_with(name)
                && !rest[name.len()..].starts_with(|c: char| c.is_alphanumeric() || c == '_')
            {
                return Span {
                    line: i + 1,
                    col: line[..at].chars().count() + 1,
                };
            }
            from = at + 3;
        }
    }
    Span { line: 0, col: 0 }
}

/// Checks a compiled script; returns every violation (in source order) and, when
/// there are none, the library call sites.
pub(crate) fn validate(source: &str, ast: &AST) -> Result<Vec<CallSite>, Vec<Violation>> {
    let mut script_fns: HashMap<&str, Vec<usize>> = HashMap::new();
    let mut violations = Vec::new();
    for f in ast.iter_functions() {
        if f.name.starts_with("anon$") {
            continue; // reported at the closure expression
        }
        script_fns.entry(f.name).or_default().push(f.params.len());
        if lookup(f.name).is_some() || f.name == "agent" {
            violations.push(Violation {
                span: fn_def_span(source, f.name),
                kind: ViolationKind::Reserved {
                    name: f.name.to_string(),
                    reason: "a plan may not redefine the robot function library".into(),
                },
            });
        }
    }
    let mut w = Walker {
        script_fns,
        violations,
        calls: Vec::new(),
    };
    ast.walk(&mut |path: &[ASTNode<'_>]| {
        w.visit(path);
        true
    });
    if w.violations.is_empty() {
        w.calls.sort_by_key(|c| c.span);
        Ok(w.calls)
    } else {
        w.violations.sort_by_key(|v| v.span);
        w.violations.dedup();
        Err(w.violations)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edit_distance_and_suggestions() {
        assert_eq!(strsim::levenshtein("kitten", "sitting"), 3);
        assert_eq!(strsim::levenshtein("", "abc"), 3);
        assert_eq!(
            suggestion("move_to_objct").as_deref(),
            Some("did you mean `move_to_object`?")
        );
        assert_eq!(suggestion("xyzzy_frobnicate"), None);
    }
}
