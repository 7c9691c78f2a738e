//! Packaging of the reduced body as an FMI 2.0 FMU: `model_description` writes
//! modelDescription.xml from the runtime's variable table (the one definition of the variables,
//! so the XML and the binary cannot disagree), `archive` zips it with the runtime binary, the
//! reduced model and the documentation.

pub mod archive;
pub mod assembly_description;
pub mod guid;
pub mod model_description;

pub use archive::{FmuArchive, write_fmu};
pub use model_description::{DefaultExperiment, ModelInfo, model_description_xml, xs_date_time};

use crate::error::BuildError;

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FmuError {
    /// The model cannot be written as a valid modelDescription.xml; the message names the
    /// variable or attribute.
    #[error("modelDescription.xml: {0}")]
    Description(String),
    /// The XML could not be written, or is not UTF-8 (`what` says which): a defect of the writer.
    #[error("modelDescription.xml: {what}: {cause}")]
    Xml {
        what: &'static str,
        #[source]
        cause: crate::error::SharedCause,
    },
}

// So that the build pipeline can use `?` on packaging steps.
impl From<FmuError> for BuildError {
    fn from(e: FmuError) -> Self {
        BuildError::internal(e.to_string()).caused_by(e)
    }
}

/// C keywords (C11 and the common C23 additions): an identifier equal to one of them could not
/// be used where importers paste the model identifier into C source (e.g. FMU export wrappers).
const C_KEYWORDS: &[&str] = &[
    "auto",
    "break",
    "case",
    "char",
    "const",
    "continue",
    "default",
    "do",
    "double",
    "else",
    "enum",
    "extern",
    "float",
    "for",
    "goto",
    "if",
    "inline",
    "int",
    "long",
    "register",
    "restrict",
    "return",
    "short",
    "signed",
    "sizeof",
    "static",
    "struct",
    "switch",
    "typedef",
    "union",
    "unsigned",
    "void",
    "volatile",
    "while",
    "bool",
    "true",
    "false",
    "nullptr",
    "alignas",
    "alignof",
    "constexpr",
    "static_assert",
    "thread_local",
    "typeof",
    "typeof_unqual",
];

/// True if `s` is a C identifier that is not a keyword and not reserved to the implementation
/// (leading underscore followed by an upper-case letter or a second underscore).
pub fn is_model_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    let Some(first) = chars.next() else { return false };
    let reserved = s.starts_with("__") || (first == '_' && s[1..].starts_with(|c: char| c.is_ascii_uppercase()));
    (first.is_ascii_alphabetic() || first == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
        && !reserved
        && !C_KEYWORDS.contains(&s)
}

/// A model identifier (a C identifier, also the binary's file name) from a model name: every
/// character outside [A-Za-z0-9_] becomes `_`; a leading digit, underscore or an empty result
/// gets the prefix `m`; a C keyword gets a trailing `_`.
pub fn model_identifier(name: &str) -> String {
    let mut id: String = name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    if !id.starts_with(|c: char| c.is_ascii_alphabetic()) {
        id.insert(0, 'm');
    }
    if C_KEYWORDS.contains(&id.as_str()) {
        id.push('_');
    }
    id
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers_are_valid_c() {
        for (name, id) in [
            ("Beam", "Beam"),
            ("my beam-2.0", "my_beam_2_0"),
            ("3D arm", "m3D_arm"),
            ("", "m"),
            ("_x", "m_x"),
            ("__X", "m__X"),
            ("Bühne", "B_hne"),
            ("int", "int_"),
        ] {
            assert_eq!(model_identifier(name), id, "{name}");
            assert!(is_model_identifier(&model_identifier(name)), "{name}");
        }
        for bad in ["", "1a", "a-b", "a.b", "_Ab", "__a", "while", "a b", "é"] {
            assert!(!is_model_identifier(bad), "{bad}");
        }
    }
}
