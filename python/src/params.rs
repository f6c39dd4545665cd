//! Parameter keys by name (`section.key`, as in the TOML files and the
//! Monte Carlo dispersions), read and edited with the rules the parameter
//! files obey: each value against its key's rule and magnitude range, then
//! the whole set against the cross-key rules ([`Params::validate`]).

use crate::error::{Error, Result};
use helicon_model::Params;
use helicon_model::params::{Descriptor, ParamError, Rule, descriptors};
use serde_json::{Map, Value, json};

/// The name edits are reported under in errors (no file is involved).
pub const ORIGIN: &str = "Params";

/// The dotted name of a descriptor.
pub fn key_of(d: &Descriptor) -> String {
    format!("{}.{}", d.section, d.key)
}

/// Every key, in file order.
pub fn keys() -> Vec<String> {
    descriptors().map(key_of).collect()
}

/// The descriptor of `key`, or the library's unknown-key error.
pub fn descriptor(key: &str) -> Result<&'static Descriptor> {
    descriptors().find(|d| key_of(d) == key).ok_or_else(|| {
        Error::from(ParamError::UnknownKey {
            file: ORIGIN.to_string(),
            line: None,
            key: key.to_string(),
        })
    })
}

/// A value as the TOML file writes it: a whole number for counts, a bool
/// for switches, a float otherwise.
fn typed(rule: Rule, v: f64) -> Value {
    match rule {
        Rule::Count => json!(v as i64),
        Rule::Flag => json!(v != 0.0),
        _ => json!(v),
    }
}

/// The value of `key`, typed as [`typed`].
pub fn get(p: &Params, key: &str) -> Result<Value> {
    let d = descriptor(key)?;
    let mut copy = *p;
    Ok(typed(d.rule, *(d.field)(&mut copy)))
}

/// `p` with the `(key, value)` edits applied, each checked against its
/// rule, then the result against the cross-key rules; on any error `p` is
/// unchanged (the edits are applied to a copy).
pub fn with_edits(p: &Params, edits: &[(String, f64)]) -> Result<Params> {
    let mut out = *p;
    for (key, v) in edits {
        let d = descriptor(key)?;
        d.check(*v).map_err(|rule| {
            Error::from(ParamError::Invalid {
                file: ORIGIN.to_string(),
                line: None,
                key: key.clone(),
                value: *v,
                rule,
            })
        })?;
        *(d.field)(&mut out) = *v;
    }
    out.validate(ORIGIN)?;
    Ok(out)
}

/// The parameters as nested tables, as the TOML file: `{"body":
/// {"mass_kg": 14.0, ...}, "servo": {"tail": {...}}, ...}`.
pub fn to_json(p: &Params) -> Value {
    let mut copy = *p;
    let mut root = Map::new();
    'keys: for d in descriptors() {
        let v = typed(d.rule, *(d.field)(&mut copy));
        let mut table = &mut root;
        for part in d.section.split('.') {
            let entry = table
                .entry(part.to_string())
                .or_insert_with(|| Value::Object(Map::new()));
            // sections are tables in the descriptor table: never a value
            let Some(next) = entry.as_object_mut() else {
                continue 'keys;
            };
            table = next;
        }
        table.insert(d.key.to_string(), v);
    }
    Value::Object(root)
}

/// What a key is: `{"unit", "symbol", "rule"}`.
pub fn describe(key: &str) -> Result<Value> {
    let d = descriptor(key)?;
    let rule = match d.rule {
        Rule::Positive => "> 0",
        Rule::NonNegative => ">= 0",
        Rule::Finite => "finite",
        Rule::Count => "whole number >= 1",
        Rule::Flag => "true/false",
    };
    Ok(json!({"unit": d.unit, "symbol": d.symbol, "rule": rule}))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edits_are_checked_and_atomic() {
        let p = Params::bergen_twin();
        let q = with_edits(&p, &[("body.mass_kg".into(), 12.0)]).unwrap();
        assert_eq!(q.body.mass_kg, 12.0);
        let e = with_edits(&p, &[("body.mass_kg".into(), -1.0)]).unwrap_err();
        assert!(
            e.message().contains("body.mass_kg") && e.message().contains("> 0"),
            "{e}"
        );
        let e = with_edits(&p, &[("body.mas_kg".into(), 1.0)]).unwrap_err();
        assert!(e.message().contains("unknown key `body.mas_kg`"), "{e}");
        let e = with_edits(&p, &[("servo.tail.s_min".into(), 0.9)]).unwrap_err();
        assert!(e.message().contains("must be < s_max"), "{e}");
        assert_eq!(p, Params::bergen_twin());
    }

    #[test]
    fn nested_tables_and_types() {
        let j = to_json(&Params::bergen_twin());
        assert_eq!(j["body"]["mass_kg"], json!(14.0));
        assert_eq!(j["main_rotor"]["blades"], json!(2));
        assert_eq!(j["servo"]["tail"]["s_min"], json!(-0.37));
        assert_eq!(j["yaw_gyro"]["enabled"], json!(false));
        assert_eq!(keys().len(), helicon_model::params::descriptor_count());
        assert_eq!(describe("body.mass_kg").unwrap()["unit"], json!("kg"));
    }
}
