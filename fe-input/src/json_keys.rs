//! Duplicate keys in the input JSON. serde_json keeps the last of two equal keys in an object
//! without a word, so `"E": 2e11, ..., "E": 2e5` would build a part a thousand times softer than
//! the first line says. This pass walks the text once, before the schema check, and refuses the
//! second key with its path and line.

use crate::error::{InputError, Result};
use serde::de::{DeserializeSeed, Error as _, MapAccess, SeqAccess, Visitor};
use std::cell::RefCell;
use std::collections::HashSet;
use std::fmt;
use std::path::Path;

/// Walks one JSON value; `duplicate` receives the path of the first repeated key.
struct Unique<'a> {
    path: String,
    duplicate: &'a RefCell<Option<String>>,
}

impl<'de> DeserializeSeed<'de> for Unique<'_> {
    type Value = ();
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> std::result::Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Unique<'_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, _: bool) -> std::result::Result<(), E> {
        Ok(())
    }
    fn visit_i64<E>(self, _: i64) -> std::result::Result<(), E> {
        Ok(())
    }
    fn visit_u64<E>(self, _: u64) -> std::result::Result<(), E> {
        Ok(())
    }
    fn visit_f64<E>(self, _: f64) -> std::result::Result<(), E> {
        Ok(())
    }
    fn visit_str<E>(self, _: &str) -> std::result::Result<(), E> {
        Ok(())
    }
    fn visit_unit<E>(self) -> std::result::Result<(), E> {
        Ok(())
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<(), A::Error> {
        let mut i = 0usize;
        while seq
            .next_element_seed(Unique { path: format!("{}[{i}]", self.path), duplicate: self.duplicate })?
            .is_some()
        {
            i += 1;
        }
        Ok(())
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> std::result::Result<(), A::Error> {
        let mut seen = HashSet::new();
        while let Some(key) = map.next_key::<String>()? {
            let path = if self.path.is_empty() { key.clone() } else { format!("{}.{key}", self.path) };
            if !seen.insert(key) {
                *self.duplicate.borrow_mut() = Some(path);
                return Err(A::Error::custom("duplicate key"));
            }
            map.next_value_seed(Unique { path, duplicate: self.duplicate })?;
        }
        Ok(())
    }
}

/// Refuses a key that appears twice in one object, naming its path and line. Malformed JSON
/// passes: the parser proper reports it with its own message.
pub fn check_unique_keys(file: &Path, text: &str) -> Result<()> {
    let duplicate = RefCell::new(None);
    let mut de = serde_json::Deserializer::from_str(text);
    let outcome = Unique { path: String::new(), duplicate: &duplicate }.deserialize(&mut de);
    match (outcome, duplicate.into_inner()) {
        (Err(e), Some(path)) => Err(InputError::field(
            file,
            path.clone(),
            format!(
                "the key \"{}\" appears twice in the same object (second time at line {}); JSON would silently keep only \
                 the last, so remove one of them",
                path.rsplit('.').next().unwrap_or(&path),
                e.line()
            ),
        )),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::check_unique_keys;
    use std::path::Path;

    #[test]
    fn a_repeated_key_is_named_with_its_path_and_line() {
        let text = "{\n \"material\": {\"E\": 2e11,\n  \"nu\": 0.3,\n  \"E\": 2e5},\n \"flanges\": []\n}";
        let e = check_unique_keys(Path::new("in.json"), text).unwrap_err().to_string();
        assert!(e.contains("in.json") && e.contains("material.E") && e.contains("line 4"), "{e}");
        let text = r#"{"flanges": [{"name": "a"}, {"name": "b", "role": 1, "name": "c"}]}"#;
        let e = check_unique_keys(Path::new("in.json"), text).unwrap_err().to_string();
        assert!(e.contains("flanges[1].name") && e.contains("twice"), "{e}");
        // equal keys in different objects are fine, and so is malformed JSON (reported elsewhere)
        check_unique_keys(Path::new("in.json"), r#"{"a": {"x": 1}, "b": {"x": 2}, "c": [{"x": 1}, {"x": 1}]}"#)
            .unwrap();
        check_unique_keys(Path::new("in.json"), r#"{"a": "#).unwrap();
    }
}
