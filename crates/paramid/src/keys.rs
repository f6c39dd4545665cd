//! Model parameters by their `helicon params` key (`section.key`, e.g.
//! `main_rotor.lift_slope_per_rad`), read and set through the model's
//! parameter table.

use helicon_model::Params;
use helicon_model::params::{Descriptor, Rule, descriptors};

/// The descriptor of `key` (`section.key`), if it is a parameter.
pub fn find(key: &str) -> Option<&'static Descriptor> {
    descriptors().find(|d| {
        key.len() == d.section.len() + 1 + d.key.len()
            && key.starts_with(d.section)
            && key[d.section.len()..].starts_with('.')
            && key.ends_with(d.key)
    })
}

/// The full key `section.key` of a descriptor.
pub fn full_key(d: &Descriptor) -> String {
    format!("{}.{}", d.section, d.key)
}

/// Whether the parameter is continuous (not a count or a switch), so that
/// it can be identified.
pub fn is_continuous(d: &Descriptor) -> bool {
    !matches!(d.rule, Rule::Count | Rule::Flag)
}

/// The value of a parameter.
pub fn get(p: &Params, d: &Descriptor) -> f64 {
    let mut copy = *p;
    *(d.field)(&mut copy)
}

/// Set a parameter (no validation: see [`Params::validate`]).
pub fn set(p: &mut Params, d: &Descriptor, v: f64) {
    *(d.field)(p) = v;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_key_is_found_and_set_round_trips() {
        let mut p = Params::bergen_twin();
        for d in descriptors() {
            let key = full_key(d);
            let found = find(&key).unwrap_or_else(|| unreachable!("{key}"));
            assert!(std::ptr::eq(found, d), "{key}");
            let v = get(&p, d);
            set(&mut p, d, v + 1.0);
            assert_eq!(get(&p, d), v + 1.0, "{key}");
            set(&mut p, d, v);
        }
        assert_eq!(p, Params::bergen_twin());
        for bad in [
            "",
            "body",
            "body.",
            ".ixx_kg_m2",
            "body.ixx",
            "bodyxixx_kg_m2",
            "servo.tail",
        ] {
            assert!(find(bad).is_none(), "{bad}");
        }
    }
}
