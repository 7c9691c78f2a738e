//! Schema violations in words a user can act on: the field, what was found, what is expected,
//! the nearest valid key for a misspelt one, and for a `oneOf` (the spec's "one of these forms")
//! either the problems inside the form the input evidently meant, or every form with what it
//! needs. Every problem is listed, not the first.

use jsonschema::error::{ValidationError, ValidationErrorKind};
use serde_json::Value;

/// One problem: the field (dotted path, `flanges[1].nodes`) and what to do about it.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    pub field: String,
    pub message: String,
}

/// The problems behind `errors`, most specific first, each once.
pub fn explain<'a>(schema: &Value, errors: impl Iterator<Item = ValidationError<'a>>) -> Vec<Problem> {
    let mut out = Vec::new();
    for e in errors {
        describe(schema, &e, &mut out);
    }
    // a oneOf's own complaint and the complaints inside it may both arrive: keep the deepest
    // fields first, and each (field, message) once
    out.sort_by_key(|p| std::cmp::Reverse(p.field.matches(['.', '[']).count()));
    let mut seen = Vec::new();
    out.retain(|p| {
        let key = (p.field.clone(), p.message.clone());
        if seen.contains(&key) {
            false
        } else {
            seen.push(key);
            true
        }
    });
    out
}

/// JSON pointer `/flanges/1/nodes` as `flanges[1].nodes`.
pub fn field_path(pointer: &str) -> String {
    let mut out = String::new();
    for token in pointer.split('/').skip(1) {
        let token = token.replace("~1", "/").replace("~0", "~");
        if token.chars().all(|c| c.is_ascii_digit()) && !token.is_empty() {
            out.push_str(&format!("[{token}]"));
        } else {
            if !out.is_empty() {
                out.push('.');
            }
            out.push_str(&token);
        }
    }
    out
}

fn join(field: &str, key: &str) -> String {
    if field.is_empty() { key.to_string() } else { format!("{field}.{key}") }
}

/// The schema object at `pointer` (a schema path), `$ref`s not followed.
fn schema_at<'s>(schema: &'s Value, pointer: &str) -> Option<&'s Value> {
    schema.pointer(pointer)
}

/// The object schema a keyword at `pointer` belongs to (`/properties/x/additionalProperties`
/// -> `/properties/x`).
fn parent<'s>(schema: &'s Value, pointer: &str) -> Option<&'s Value> {
    let cut = pointer.rfind('/')?;
    schema_at(schema, &pointer[..cut])
}

/// Keys the object schema allows, following one `$ref` to `$defs`.
fn allowed_keys(schema: &Value, object: &Value) -> Vec<String> {
    let resolved = match object.get("$ref").and_then(Value::as_str) {
        Some(r) if r.starts_with("#/") => schema.pointer(&r[1..]).unwrap_or(object),
        _ => object,
    };
    resolved.get("properties").and_then(Value::as_object).map(|p| p.keys().cloned().collect()).unwrap_or_default()
}

/// The allowed key nearest to `key` by edit distance, if it is near enough to be a typo.
pub fn nearest<'k>(key: &str, allowed: &'k [String]) -> Option<&'k str> {
    let lower = key.to_lowercase();
    allowed
        .iter()
        .map(|a| (strsim::levenshtein(&lower, &a.to_lowercase()), a))
        .filter(|(d, a)| *d <= 2.max(a.len() / 3) && *d < a.len())
        .min_by_key(|(d, _)| *d)
        .map(|(_, a)| a.as_str())
}

fn short(value: &Value) -> String {
    cut(&value.to_string())
}

/// Longest quoted value or key a message repeats: a 100 KB string pasted into a field is
/// recognisable by its start, and a message that echoes it in full buries the field and the fix.
const QUOTED_CHARS: usize = 60;

fn cut(text: &str) -> String {
    if text.chars().count() > QUOTED_CHARS {
        format!("{}... ({} characters)", text.chars().take(QUOTED_CHARS - 3).collect::<String>(), text.chars().count())
    } else {
        text.to_string()
    }
}

/// The validator's own sentence ("... is greater than the maximum of 1000"), which quotes the
/// instance in full: quoted as `short` does instead.
fn said(e: &ValidationError<'_>) -> String {
    let text = e.to_string();
    let full = e.instance().to_string();
    if full.chars().count() > QUOTED_CHARS { text.replace(&full, &short(e.instance())) } else { text }
}

fn describe(schema: &Value, e: &ValidationError<'_>, out: &mut Vec<Problem>) {
    let field = field_path(&e.instance_path().to_string());
    let schema_path = e.schema_path().to_string();
    match e.kind() {
        ValidationErrorKind::AdditionalProperties { unexpected } => {
            let allowed = parent(schema, &schema_path).map(|o| allowed_keys(schema, o)).unwrap_or_default();
            for key in unexpected {
                let hint = match nearest(key, &allowed) {
                    Some(near) => format!("did you mean \"{near}\"? "),
                    None => String::new(),
                };
                let key = cut(key);
                out.push(Problem {
                    field: join(&field, &key),
                    message: format!("unknown key \"{key}\"; {hint}allowed here: {}", allowed.join(", ")),
                });
            }
        }
        ValidationErrorKind::OneOfNotValid { context } | ValidationErrorKind::AnyOf { context } => {
            one_of(schema, e, &field, &schema_path, context, out);
        }
        ValidationErrorKind::FalseSchema => {
            // a key the object's other fields rule out (an axis on a spherical joint)
            let key = field.rsplit(['.', '[']).next().unwrap_or(&field).trim_end_matches(']').to_string();
            out.push(Problem {
                field: field.clone(),
                message: format!(
                    "found {}: \"{key}\" is not allowed here, given the object's other fields",
                    short(e.instance())
                ),
            });
        }
        ValidationErrorKind::Required { property } => {
            let key = property.as_str().unwrap_or_default();
            out.push(Problem { field: join(&field, key), message: format!("\"{key}\" is missing and required here") });
        }
        ValidationErrorKind::Enum { options } => {
            let found = e.instance();
            let choices: Vec<String> =
                options.as_array().map(|a| a.iter().map(short).collect()).unwrap_or_else(|| vec![short(options)]);
            let names: Vec<String> = choices.iter().map(|c| c.trim_matches('"').to_string()).collect();
            let hint = found
                .as_str()
                .and_then(|f| nearest(f, &names))
                .map(|n| format!(" (did you mean \"{n}\"?)"))
                .unwrap_or_default();
            out.push(Problem {
                field,
                message: format!("found {}, expected one of {}{hint}", short(found), choices.join(", ")),
            });
        }
        ValidationErrorKind::Minimum { .. }
        | ValidationErrorKind::Maximum { .. }
        | ValidationErrorKind::ExclusiveMinimum { .. }
        | ValidationErrorKind::ExclusiveMaximum { .. } => {
            // the range and what it stands for (the property's description): a value off by a
            // unit slip says so, not only that it is too small
            let why = parent(schema, &schema_path)
                .and_then(|p| p.get("description"))
                .and_then(Value::as_str)
                .map(|d| format!(" ({d})"))
                .unwrap_or_default();
            let range = parent(schema, &schema_path).map(range_of).unwrap_or_default();
            out.push(Problem {
                field,
                message: format!("found {}, outside {range}: {}{why}", short(e.instance()), said(e)),
            });
        }
        _ => {
            out.push(Problem { field, message: format!("found {}: {}", short(e.instance()), said(e)) });
        }
    }
}

/// A bound as a person writes it: 1000, 0.49999, 1e13, 1e-14.
fn number(x: f64) -> String {
    if x == 0.0 || (1e-3..1e6).contains(&x.abs()) { format!("{x}") } else { format!("{x:e}") }
}

/// The numeric range a property schema allows, as "[0, 1e6]" or "(0, inf)".
fn range_of(property: &Value) -> String {
    let bound = |key: &str| property.get(key).and_then(Value::as_f64).map(number);
    let (lo, lo_open) = match (bound("minimum"), bound("exclusiveMinimum")) {
        (_, Some(x)) => (x, true),
        (Some(x), None) => (x, false),
        (None, None) => ("-inf".to_string(), true),
    };
    let (hi, hi_open) = match (bound("maximum"), bound("exclusiveMaximum")) {
        (_, Some(x)) => (x, true),
        (Some(x), None) => (x, false),
        (None, None) => ("inf".to_string(), true),
    };
    format!("{}{lo}, {hi}{}", if lo_open { '(' } else { '[' }, if hi_open { ')' } else { ']' })
}

/// A `oneOf` (or `anyOf`) that no alternative satisfies. Where the input picks one of them (the
/// alternative's failures all lie inside the value, deeper than the alternative's own keys, or
/// it names the alternative's required key), those failures are what to fix; otherwise every
/// alternative is listed with what it needs.
fn one_of(
    schema: &Value,
    e: &ValidationError<'_>,
    field: &str,
    schema_path: &str,
    context: &[Vec<ValidationError<'static>>],
    out: &mut Vec<Problem>,
) {
    let alternatives = schema_at(schema, schema_path).and_then(Value::as_array);
    let instance = e.instance();
    let present: Vec<&str> = instance.as_object().map(|o| o.keys().map(String::as_str).collect()).unwrap_or_default();
    // the alternative the input means: the only one whose failures are all inside the value
    // (a misspelt key in a `plane`, a missing radius of a `sphere`), none of them a wrong form
    // (a required key of the form itself missing, a `method` naming another form)
    let depth = e.instance_path().to_string().matches('/').count();
    let meant_by = |errors: &[ValidationError<'static>]| {
        errors.iter().all(|inner| {
            let d = inner.instance_path().to_string().matches('/').count().saturating_sub(depth);
            let wrong_form = matches!(
                inner.kind(),
                ValidationErrorKind::Required { .. }
                    | ValidationErrorKind::Not { .. }
                    | ValidationErrorKind::Type { .. }
                    | ValidationErrorKind::Constant { .. }
                    | ValidationErrorKind::Enum { .. }
                    | ValidationErrorKind::OneOfNotValid { .. }
                    | ValidationErrorKind::AnyOf { .. }
            );
            !(d == 0 && wrong_form
                || d == 1
                    && matches!(inner.kind(), ValidationErrorKind::Constant { .. } | ValidationErrorKind::Enum { .. }))
        })
    };
    let candidates: Vec<usize> = (0..context.len()).filter(|&i| meant_by(&context[i])).collect();
    let meant = (candidates.len() == 1).then(|| candidates[0]);
    if let Some(i) = meant
        && let Some(errors) = context.get(i)
        && !errors.is_empty()
    {
        for inner in errors {
            describe(schema, inner, out);
        }
        return;
    }
    let forms: Vec<String> = alternatives
        .map(|alts| {
            alts.iter()
                .enumerate()
                .map(|(i, alt)| match alt.get("description").and_then(Value::as_str) {
                    Some(d) => format!("({}) {d}", i + 1),
                    None => {
                        let required: Vec<String> = alt
                            .get("required")
                            .and_then(Value::as_array)
                            .map(|r| r.iter().filter_map(Value::as_str).map(|k| format!("\"{k}\"")).collect())
                            .unwrap_or_default();
                        format!("({}) with {}", i + 1, required.join(" and "))
                    }
                })
                .collect()
        })
        .unwrap_or_default();
    let found = if present.is_empty() {
        format!("found {}", short(instance))
    } else {
        format!("found the keys {}", present.iter().map(|k| format!("\"{k}\"")).collect::<Vec<_>>().join(", "))
    };
    // a key that names no form but is a slip of one's key ("box_fce" for "box_face")
    let form_keys: Vec<String> = alternatives
        .map(|alts| {
            alts.iter()
                .filter_map(|alt| alt.get("required").and_then(Value::as_array))
                .flatten()
                .filter_map(Value::as_str)
                .map(str::to_string)
                .collect()
        })
        .unwrap_or_default();
    let hints: Vec<String> = present
        .iter()
        .filter(|k| !form_keys.iter().any(|f| f == *k))
        .filter_map(|k| nearest(k, &form_keys).map(|near| format!("did you mean \"{near}\" for \"{}\"?", cut(k))))
        .collect();
    let hint = if hints.is_empty() { String::new() } else { format!(" ({})", hints.join("; ")) };
    out.push(Problem {
        field: field.to_string(),
        message: format!("{found}{hint}, which matches none of the forms this field takes: {}", forms.join("; ")),
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_key_finds_typos_and_not_strangers() {
        let allowed: Vec<String> =
            ["modes", "method", "max_frequency", "normal"].iter().map(|s| s.to_string()).collect();
        assert_eq!(nearest("mode", &allowed), Some("modes"));
        assert_eq!(nearest("normale", &allowed), Some("normal"));
        assert_eq!(nearest("Method", &allowed), Some("method"));
        assert_eq!(nearest("colour", &allowed), None);
    }

    #[test]
    fn pointers_become_fields() {
        assert_eq!(field_path("/flanges/1/nodes"), "flanges[1].nodes");
        assert_eq!(field_path(""), "");
    }
}
