//! Values that cross between scripts and the host: object records, the `agent`
//! handle, and conversion of script values to JSON for the trace.

use rhai::Dynamic;
use serde::{Deserialize, Serialize};
use std::fmt;

/// An object record as `get_obj_attributes` returns it. Scripts read its fields
/// (`obj.name`, `obj.colour`, `obj.label_id`, `obj.id`, `obj.position`, `obj.count`)
/// and pass it back to library functions, which resolve it by `id`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectRecord {
    /// Instance id in the map.
    pub id: u32,
    /// Category label, e.g. "table".
    pub name: String,
    /// 1-based index among instances of the same class (the paper's label_id).
    pub label_id: u32,
    /// Colour word, if known.
    pub colour: Option<String>,
    /// Footprint centre `[x, y]`, metres.
    pub position: [f64; 2],
    /// Number of instances of the same class in the map.
    pub count: u32,
}

impl fmt::Display for ObjectRecord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.colour {
            Some(c) => write!(f, "{c} {} #{}", self.name, self.label_id),
            None => write!(f, "{} #{}", self.name, self.label_id),
        }
    }
}

/// The `agent` value scripts call library functions on (`agent.move_to(...)`).
/// It carries nothing: the run's context travels in the engine's tag.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct AgentHandle;

/// Longest array or map kept whole in the trace; longer ones keep their head and a
/// note of how many elements were left out.
const TRACE_MAX_ITEMS: usize = 32;
/// Longest string kept whole in the trace, in bytes.
const TRACE_MAX_STRING: usize = 256;

fn short_string(s: &str) -> serde_json::Value {
    if s.len() <= TRACE_MAX_STRING {
        return serde_json::Value::String(s.to_string());
    }
    let mut cut = TRACE_MAX_STRING;
    while !s.is_char_boundary(cut) {
        cut -= 1;
    }
    serde_json::Value::String(format!("{}… ({} bytes)", &s[..cut], s.len()))
}

/// Converts a script value to JSON for the trace (numbers, strings, arrays, maps,
/// object records; anything else as its display string). Large values are
/// abbreviated so that the trace stays small whatever a script passes.
pub(crate) fn to_json(v: &Dynamic) -> serde_json::Value {
    use serde_json::Value;
    if v.is_unit() {
        return Value::Null;
    }
    if let Ok(b) = v.as_bool() {
        return Value::Bool(b);
    }
    if let Ok(i) = v.as_int() {
        return Value::from(i);
    }
    if let Ok(x) = v.as_float() {
        return serde_json::Number::from_f64(x)
            .map(Value::Number)
            .unwrap_or_else(|| Value::String(x.to_string()));
    }
    if let Ok(c) = v.as_char() {
        return Value::String(c.to_string());
    }
    if let Some(s) = v.read_lock::<rhai::ImmutableString>() {
        return short_string(&s);
    }
    if let Some(a) = v.read_lock::<rhai::Array>() {
        let mut out: Vec<Value> = a.iter().take(TRACE_MAX_ITEMS).map(to_json).collect();
        if a.len() > TRACE_MAX_ITEMS {
            out.push(Value::String(format!(
                "… ({} more)",
                a.len() - TRACE_MAX_ITEMS
            )));
        }
        return Value::Array(out);
    }
    if let Some(m) = v.read_lock::<rhai::Map>() {
        let mut out: serde_json::Map<String, Value> = m
            .iter()
            .take(TRACE_MAX_ITEMS)
            .map(|(k, v)| {
                (
                    short_string(k).as_str().unwrap_or_default().to_string(),
                    to_json(v),
                )
            })
            .collect();
        if m.len() > TRACE_MAX_ITEMS {
            out.insert("…".into(), Value::from(m.len() - TRACE_MAX_ITEMS));
        }
        return Value::Object(out);
    }
    if let Some(o) = v.read_lock::<ObjectRecord>() {
        return serde_json::to_value(&*o).unwrap_or(Value::Null);
    }
    if v.is::<AgentHandle>() {
        return Value::String("agent".into());
    }
    short_string(v.type_name())
}

/// `[x, y]` as a script array.
pub(crate) fn point_to_dynamic(p: [f64; 2]) -> Dynamic {
    Dynamic::from_array(vec![Dynamic::from_float(p[0]), Dynamic::from_float(p[1])])
}

/// A short description of a value's type for error messages.
pub(crate) fn type_word(v: &Dynamic) -> String {
    if v.is_unit() {
        "nothing (unit)".into()
    } else if v.is_int() {
        format!("integer {}", v)
    } else if v.is_float() {
        format!("number {}", v)
    } else if v.is_string() {
        format!("string {:?}", v.to_string())
    } else if v.is_array() {
        "an array".into()
    } else if v.is_map() {
        "a map".into()
    } else if v.is::<ObjectRecord>() {
        "an object record".into()
    } else if v.is::<AgentHandle>() {
        "agent".into()
    } else {
        v.type_name().to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_of_values() {
        let rec = ObjectRecord {
            id: 7,
            name: "table".into(),
            label_id: 3,
            colour: Some("yellow".into()),
            position: [1.0, 2.5],
            count: 4,
        };
        assert_eq!(rec.to_string(), "yellow table #3");
        let j = to_json(&Dynamic::from(rec));
        assert_eq!(j["id"], 7);
        assert_eq!(j["colour"], "yellow");
        assert_eq!(
            to_json(&point_to_dynamic([1.0, -2.0])),
            serde_json::json!([1.0, -2.0])
        );
        assert_eq!(to_json(&Dynamic::UNIT), serde_json::Value::Null);
        assert_eq!(to_json(&Dynamic::from_float(f64::NAN)), "NaN");
        assert_eq!(type_word(&Dynamic::from("x")), "string \"x\"");
        let big: rhai::Array = (0..100).map(Dynamic::from_int).collect();
        let j = to_json(&Dynamic::from_array(big));
        assert_eq!(j.as_array().map(Vec::len), Some(33));
        assert_eq!(j[32], "… (68 more)");
        let long = to_json(&Dynamic::from("y".repeat(1000)));
        assert_eq!(long, format!("{}… (1000 bytes)", "y".repeat(256)));
    }
}
