//! Step 2 answers: the plan script inside the model's text.
//!
//! [`extract_code`] takes the first fenced block (```` ```rhai ````, ```` ```python ````, or
//! any other tag, or none); without a fence the whole answer is the candidate.
//! [`pythonic_fixups`] repairs the Python habits a model brings from the paper's prompts
//! (`#` comments, single-quoted strings, `None`/`True`/`False`, missing semicolons) without
//! changing what a well-formed script means; the pipeline applies it only when the raw
//! script does not compile.

/// The script in a model's answer: the body of the first fenced code block (an unterminated
/// fence runs to the end of the text), else the whole text, trimmed.
#[must_use]
pub fn extract_code(text: &str) -> String {
    let Some(open) = text.find("```") else {
        return text.trim().to_string();
    };
    let after = &text[open + 3..];
    // The info string (language tag) runs to the end of the line.
    let body_start = after.find('\n').map_or(after.len(), |i| i + 1);
    let tag = after[..body_start].trim();
    let body = &after[body_start..];
    let body = match body.find("```") {
        Some(close) => &body[..close],
        None => body,
    };
    // "```agent.face(x)```" on one line: the tag is really code.
    if body.trim().is_empty() && !tag.is_empty() && tag.contains('(') {
        return tag.trim_end_matches("```").trim().to_string();
    }
    body.trim().to_string()
}

/// Rewrites Python-isms into Rhai, line by line, outside string literals:
/// `#` comments become `//`, `'text'` becomes `"text"`, `None`/`True`/`False` become
/// `()`/`true`/`false`, and a line that ends a statement without `;` gets one.
#[must_use]
pub fn pythonic_fixups(src: &str) -> String {
    let mut declared: Vec<String> = Vec::new();
    let lines: Vec<String> = src
        .lines()
        .map(fix_line)
        .map(|l| declare_assignment(&l, &mut declared))
        .collect();
    let mut out = String::new();
    for (i, line) in lines.iter().enumerate() {
        let next = lines[i + 1..]
            .iter()
            .map(|l| code_part(l).trim())
            .find(|l| !l.is_empty())
            .unwrap_or("");
        out.push_str(line);
        if needs_semicolon(code_part(line).trim_end(), next) {
            // Put the semicolon before any trailing comment.
            let code_len = code_part(line).trim_end().len();
            out.truncate(out.len() - line.len());
            out.push_str(&line[..code_len]);
            out.push(';');
            out.push_str(&line[code_len..]);
        }
        out.push('\n');
    }
    out
}

/// `x = value` for a variable never declared becomes `let x = value` (Python declares by
/// assigning; Rhai needs `let`).
fn declare_assignment(line: &str, declared: &mut Vec<String>) -> String {
    let trimmed = line.trim_start();
    let indent = &line[..line.len() - trimmed.len()];
    if let Some(rest) = trimmed
        .strip_prefix("let ")
        .or_else(|| trimmed.strip_prefix("const "))
    {
        let name: String = rest
            .trim_start()
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        declared.push(name);
        return line.to_string();
    }
    let name: String = trimmed
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect();
    let rest = trimmed[name.len()..].trim_start();
    let is_assign = !name.is_empty()
        && !name.starts_with(|c: char| c.is_ascii_digit())
        && rest.starts_with('=')
        && !rest.starts_with("==");
    if is_assign && !declared.contains(&name) {
        declared.push(name);
        return format!("{indent}let {trimmed}");
    }
    line.to_string()
}

/// The line without a trailing `//` comment (outside strings).
fn code_part(line: &str) -> &str {
    let mut in_str = false;
    let bytes = line.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'"' => in_str = !in_str,
            b'\\' if in_str => i += 1,
            b'/' if !in_str && bytes.get(i + 1) == Some(&b'/') => return &line[..i],
            _ => {}
        }
        i += 1;
    }
    line
}

fn needs_semicolon(code: &str, next: &str) -> bool {
    if code.is_empty() {
        return false;
    }
    let last = code.chars().last().unwrap_or(' ');
    let ends_value =
        last == ')' || last == ']' || last == '"' || last.is_alphanumeric() || last == '_';
    if !ends_value {
        return false;
    }
    let first_word = code.split_whitespace().next().unwrap_or("");
    if matches!(
        first_word,
        "if" | "else" | "for" | "while" | "loop" | "fn" | "}"
    ) && !code.ends_with(')')
    {
        return false;
    }
    if matches!(first_word, "if" | "for" | "while" | "fn") {
        return false;
    }
    // A continued expression: the next line starts with an operator or a method call.
    let cont = next.starts_with('.')
        || next.starts_with('+')
        || next.starts_with('*')
        || next.starts_with('/')
        || next.starts_with("&&")
        || next.starts_with("||")
        || next.starts_with("else")
        || next.starts_with(')')
        || next.starts_with(']');
    !cont
}

fn fix_line(line: &str) -> String {
    let mut out = String::with_capacity(line.len() + 2);
    let chars: Vec<char> = line.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        match c {
            '"' => {
                // Copy a double-quoted string verbatim.
                out.push(c);
                i += 1;
                while i < chars.len() {
                    out.push(chars[i]);
                    if chars[i] == '\\' && i + 1 < chars.len() {
                        out.push(chars[i + 1]);
                        i += 2;
                        continue;
                    }
                    if chars[i] == '"' {
                        break;
                    }
                    i += 1;
                }
                i += 1;
            }
            '\'' => {
                // A single-quoted string (Rhai reads '...' as one character).
                let end = chars[i + 1..].iter().position(|&d| d == '\'');
                match end {
                    Some(len) => {
                        let s: String = chars[i + 1..i + 1 + len].iter().collect();
                        out.push('"');
                        out.push_str(&s.replace('"', "\\\""));
                        out.push('"');
                        i += len + 2;
                    }
                    None => {
                        out.push(c);
                        i += 1;
                    }
                }
            }
            '#' => {
                out.push_str("//");
                out.extend(&chars[i + 1..]);
                break;
            }
            '/' if chars.get(i + 1) == Some(&'/') => {
                out.extend(&chars[i..]);
                break;
            }
            c if c.is_alphabetic() || c == '_' => {
                let start = i;
                while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                    i += 1;
                }
                let word: String = chars[start..i].iter().collect();
                let prev_dot = start > 0 && chars[start - 1] == '.';
                out.push_str(match word.as_str() {
                    "None" if !prev_dot => "()",
                    "True" if !prev_dot => "true",
                    "False" if !prev_dot => "false",
                    _ => &word,
                });
            }
            _ => {
                out.push(c);
                i += 1;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_fenced_block_wins() {
        let t = "Here you go:\n```rhai\nlet t = agent.get_obj_attributes(\"table\", 3, \"yellow\");\nagent.face(t);\n```\nand also\n```\nnope\n```";
        assert_eq!(
            extract_code(t),
            "let t = agent.get_obj_attributes(\"table\", 3, \"yellow\");\nagent.face(t);"
        );
        assert_eq!(
            extract_code("```python\nagent.turn(90)\n```"),
            "agent.turn(90)"
        );
        assert_eq!(extract_code("```\nagent.turn(90);"), "agent.turn(90);");
        assert_eq!(extract_code("  agent.turn(90);  "), "agent.turn(90);");
        assert_eq!(extract_code("```agent.turn(90);```"), "agent.turn(90);");
    }

    #[test]
    fn python_habits_become_rhai() {
        let py = "# go to the sofa\nobj = agent.get_obj_attributes('sofa', 0, None)\nagent.move_to_object(obj)  # there\n";
        let rhai = pythonic_fixups(py);
        assert_eq!(
            rhai,
            "// go to the sofa\nlet obj = agent.get_obj_attributes(\"sofa\", 0, ());\nagent.move_to_object(obj);  // there\n"
        );
    }

    #[test]
    fn fixups_keep_rhai_intact() {
        let src = "let t = agent.get_obj_attributes(\"it's\", 1, \"\");\nif true {\n    agent.face(t);\n}\nfor i in range(0, 4) {\n    agent.turn(90);\n}\n";
        assert_eq!(pythonic_fixups(src), src);
    }

    #[test]
    fn continued_lines_get_no_semicolon() {
        let src = "let x = 1\n    + 2\nagent.move_forward(x)";
        assert_eq!(
            pythonic_fixups(src),
            "let x = 1\n    + 2;\nagent.move_forward(x);\n"
        );
    }
}
