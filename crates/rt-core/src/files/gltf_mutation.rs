//! Structure-aware damage to a glTF file's JSON, for fuzzing the loader
//! with files that parse as glTF but say something wrong: the damage a
//! byte-level fuzzer rarely gets past the JSON parser with.
//!
//! A mutation picks one value of the document (every object member, array
//! element and number is a candidate, equally likely) and either changes a
//! number (to 0, −1, a neighbour, a large or fractional value, or an index
//! just past the end of the array it likely points into), drops an object
//! member, swaps the value's type (number ↔ string, array ↔ object, null,
//! boolean), or duplicates or empties an array. The choices come from a
//! [`Choices`] stream, so the same seed (unit tests) or the same fuzzer
//! input (`fuzz/fuzz_targets/gltf_json.rs`) gives the same file.
//!
//! Self-contained (serde_json only, no `crate::` paths) so the fuzz crate
//! includes this very file with `#[path]`.

use serde_json::{Map, Number, Value};

/// Where a mutation's choices come from: a seeded generator or a fuzzer's
/// bytes.
pub enum Choices<'a> {
    /// SplitMix64 (Steele, Lea & Flood 2014) from this state.
    Seeded(u64),
    /// These bytes, two per choice, then zeros.
    Bytes(&'a [u8]),
}

impl Choices<'_> {
    /// A choice in `0..n` (`n ≥ 1`).
    pub fn below(&mut self, n: usize) -> usize {
        let raw = match self {
            Choices::Seeded(state) => {
                *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
                let mut z = *state;
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                z ^ (z >> 31)
            }
            Choices::Bytes(bytes) => {
                let (head, rest) = bytes.split_at(bytes.len().min(2));
                *bytes = rest;
                head.iter().fold(0u64, |acc, &b| acc << 8 | u64::from(b))
            }
        };
        (raw % n.max(1) as u64) as usize
    }
}

/// `doc` with `count` mutations applied one after another.
pub fn mutate(doc: &mut Value, count: usize, choices: &mut Choices) {
    for _ in 0..count {
        mutate_once(doc, choices);
    }
}

/// How many values `v` holds, itself included.
fn size(v: &Value) -> usize {
    1 + match v {
        Value::Array(a) => a.iter().map(size).sum(),
        Value::Object(o) => o.values().map(size).sum(),
        _ => 0,
    }
}

/// One mutation of a value chosen uniformly among all of `doc`'s.
fn mutate_once(doc: &mut Value, choices: &mut Choices) {
    let mut target = choices.below(size(doc));
    // The length of the array the chosen value sits in (or of the
    // document's largest top-level array): indices point into arrays like it.
    let largest = doc
        .as_object()
        .map_or(1, |o| o.values().filter_map(Value::as_array).map(Vec::len).max().unwrap_or(1));
    let mut v = doc;
    loop {
        if target == 0 {
            break;
        }
        target -= 1;
        let next = match v {
            Value::Array(a) => {
                let mut found = None;
                for (k, e) in a.iter().enumerate() {
                    let s = size(e);
                    if target < s {
                        found = Some(k);
                        break;
                    }
                    target -= s;
                }
                found.map(|k| &mut a[k])
            }
            Value::Object(o) => {
                let mut found = None;
                for (k, e) in o.iter() {
                    let s = size(e);
                    if target < s {
                        found = Some(k.clone());
                        break;
                    }
                    target -= s;
                }
                // Drop a member now and then instead of going into it.
                match found {
                    Some(key) if target == 0 && choices.below(4) == 0 => {
                        o.remove(&key);
                        return;
                    }
                    Some(key) => o.get_mut(&key),
                    None => None,
                }
            }
            _ => None,
        };
        match next {
            Some(n) => v = n,
            None => return,
        }
    }
    *v = replacement(v, largest, choices);
}

/// What the chosen value becomes.
fn replacement(v: &Value, largest: usize, choices: &mut Choices) -> Value {
    let number = |x: f64| Number::from_f64(x).map_or(Value::Null, Value::Number);
    match (v, choices.below(3)) {
        (Value::Number(n), 0 | 1) => {
            let x = n.as_f64().unwrap_or(0.0);
            let i = n.as_i64().unwrap_or(0);
            match choices.below(10) {
                0 => Value::from(0),
                1 => Value::from(-1),
                2 => Value::from(i.saturating_add(1)),
                3 => Value::from(i.saturating_sub(1)),
                4 => Value::from(largest as i64),
                5 => Value::from(largest as i64 + 1),
                6 => Value::from(u32::MAX),
                7 => number(x * 1e30),
                8 => number(x + 0.5),
                _ => Value::from(i64::MAX),
            }
        }
        (Value::Array(a), 0) => match choices.below(3) {
            0 => Value::Array(Vec::new()),
            1 => Value::Array(a.iter().chain(a.iter()).cloned().collect()),
            _ => Value::Array(a[..a.len() / 2].to_vec()),
        },
        (Value::Object(o), 0) => {
            let mut o: Map<String, Value> = o.clone();
            let keys: Vec<String> = o.keys().cloned().collect();
            if !keys.is_empty() {
                o.remove(&keys[choices.below(keys.len())]);
            }
            Value::Object(o)
        }
        (Value::String(s), 0) => Value::String(match choices.below(4) {
            0 => String::new(),
            1 => format!("{s}%"),
            2 => "image/gif".into(),
            _ => s.chars().rev().collect(),
        }),
        _ => match choices.below(7) {
            0 => Value::Null,
            1 => Value::Bool(true),
            2 => Value::from("x"),
            3 => Value::Array(vec![Value::from(0)]),
            4 => Value::Object(Map::new()),
            5 => number(f64::MAX),
            _ => Value::from(-7),
        },
    }
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;

    fn doc() -> Value {
        json!({ "accessors": [{ "count": 3, "type": "VEC3" }, { "count": 3 }], "scene": 0, "asset": { "version": "2.0" } })
    }

    #[test]
    fn the_same_choices_give_the_same_mutant_and_mutants_differ_from_the_document() {
        let (mut changed, mut distinct) = (0, std::collections::HashSet::new());
        for seed in 0..200 {
            let (mut a, mut b) = (doc(), doc());
            mutate(&mut a, 2, &mut Choices::Seeded(seed));
            mutate(&mut b, 2, &mut Choices::Seeded(seed));
            assert_eq!(a, b, "seed {seed}");
            changed += usize::from(a != doc());
            distinct.insert(a.to_string());
        }
        // A mutation can put back what was there (a number set to its own
        // value): nearly all differ, and in many ways.
        assert!(changed > 180 && distinct.len() > 100, "{changed} changed, {} distinct", distinct.len());
    }

    #[test]
    fn fuzzer_bytes_are_read_two_per_choice_then_zeros() {
        let mut choices = Choices::Bytes(&[1, 2, 3]);
        assert_eq!(choices.below(1000), 258);
        assert_eq!(choices.below(1000), 3);
        assert_eq!(choices.below(1000), 0);
        // Dropping members and swapping types happen: some mutants lose a key.
        let dropped = (0..300u64).any(|seed| {
            let mut v = doc();
            mutate(&mut v, 1, &mut Choices::Seeded(seed));
            v.as_object().is_some_and(|o| o.len() < 3)
        });
        assert!(dropped);
    }
}
