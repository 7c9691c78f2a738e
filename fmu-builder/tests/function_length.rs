//! No library function of the builder is longer than `LIMIT` lines: a long function does several
//! jobs, and each job read (and tested) on its own is easier to trust. Tests are exempt: the
//! `#[cfg(test)]` modules, files named `tests.rs` or under a `tests/` folder, and `#[test]` fns.
//!
//! The scanner blanks comments and string and char literals first (so a brace or a `fn` inside
//! them is not code), then finds every `fn` item with a body and its extent by brace matching.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The most lines a function item may span, from its `fn` line to its closing brace.
const LIMIT: usize = 80;

#[derive(Debug, PartialEq)]
struct Function {
    name: String,
    /// 1-based lines of the `fn` keyword and of the body's closing brace.
    first_line: usize,
    last_line: usize,
}

impl Function {
    fn lines(&self) -> usize {
        self.last_line - self.first_line + 1
    }
}

/// What a file holds: its functions outside test code, and the `#[cfg(test)] mod name;`
/// declarations, whose files are test code too.
#[derive(Debug, Default)]
struct Scan {
    functions: Vec<Function>,
    test_modules: Vec<String>,
}

/// `src` with every comment and the contents of every string, byte string, raw string and char
/// literal replaced by spaces; newlines stay, so lines keep their numbers.
fn code_only(src: &str) -> String {
    let s: Vec<char> = src.chars().collect();
    let mut out: Vec<char> = Vec::with_capacity(s.len());
    let blank = |c: char| if c == '\n' { '\n' } else { ' ' };
    let mut i = 0;
    while i < s.len() {
        let c = s[i];
        let next = s.get(i + 1).copied();
        let previous_is_word = i > 0 && (s[i - 1].is_alphanumeric() || s[i - 1] == '_');
        if c == '/' && next == Some('/') {
            while i < s.len() && s[i] != '\n' {
                out.push(' ');
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < s.len() {
                if s[i] == '/' && s.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push(' ');
                    out.push(' ');
                    i += 2;
                } else if s[i] == '*' && s.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push(' ');
                    out.push(' ');
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    out.push(blank(s[i]));
                    i += 1;
                }
            }
        } else if let Some(hashes) = raw_string_start(&s, i, previous_is_word) {
            // r"..." / r#"..."# / br#"..."#: no escapes, ends at a quote and as many hashes
            let open = s[i..].iter().position(|&x| x == '"').unwrap_or(0) + i;
            out.extend(&s[i..=open]);
            i = open + 1;
            while i < s.len()
                && !(s[i] == '"' && s[i + 1..].iter().take(hashes).filter(|&&x| x == '#').count() == hashes)
            {
                out.push(blank(s[i]));
                i += 1;
            }
            let end = (i + 1 + hashes).min(s.len());
            out.extend(&s[i.min(s.len())..end]);
            i = end;
        } else if c == '"' {
            out.push('"');
            i += 1;
            while i < s.len() && s[i] != '"' {
                let step = if s[i] == '\\' { 2 } else { 1 };
                for k in i..(i + step).min(s.len()) {
                    out.push(blank(s[k]));
                }
                i += step;
            }
            if i < s.len() {
                out.push('"');
                i += 1;
            }
        } else if c == '\'' {
            // a char literal ('x', '\n', '\u{7b}', '\'') or a lifetime ('a), which has no closing quote
            let end = if next == Some('\\') {
                s[i + 2..].iter().position(|&x| x == '\'').map(|p| i + 2 + p + 1)
            } else if s.get(i + 2) == Some(&'\'') {
                Some(i + 3)
            } else {
                None
            };
            match end {
                Some(end) => {
                    out.push('\'');
                    out.extend(std::iter::repeat_n(' ', end - i - 2));
                    out.push('\'');
                    i = end;
                }
                None => {
                    out.push(c);
                    i += 1;
                }
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out.into_iter().collect()
}

/// The number of hashes of a raw string starting at `i` (`r"`, `r#"`, `br##"` ...), or `None`.
fn raw_string_start(s: &[char], i: usize, previous_is_word: bool) -> Option<usize> {
    if previous_is_word {
        return None;
    }
    let mut j = i;
    if s[j] == 'b' {
        j += 1;
    }
    if s.get(j) != Some(&'r') {
        return None;
    }
    j += 1;
    let hashes = s[j..].iter().take_while(|&&x| x == '#').count();
    (s.get(j + hashes) == Some(&'"')).then_some(hashes)
}

fn is_word(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// The index of the brace closing the one at `open`.
fn matching_brace(code: &[u8], open: usize) -> usize {
    let mut depth = 0usize;
    for (k, &c) in code.iter().enumerate().skip(open) {
        match c {
            b'{' => depth += 1,
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    return k;
                }
            }
            _ => {}
        }
    }
    code.len() - 1
}

/// Whether an attribute's text (between `#[` and `]`) marks test-only code.
fn is_test_attribute(attribute: &str) -> bool {
    let attribute: String = attribute.chars().filter(|c| !c.is_whitespace()).collect();
    attribute == "test" || attribute == "cfg(test)" || attribute.starts_with("cfg(all(test,")
}

/// The `fn` items of one file's source, test code left out.
fn scan(src: &str) -> Scan {
    let code = code_only(src);
    let code = code.as_bytes();
    let line_of = |at: usize| code[..at].iter().filter(|&&c| c == b'\n').count() + 1;
    let word_at = |at: usize| {
        let end = at + code[at..].iter().take_while(|&&c| is_word(c)).count();
        std::str::from_utf8(&code[at..end]).unwrap_or("")
    };
    let mut result = Scan::default();
    let mut test_item = false;
    let mut i = 0;
    while i < code.len() {
        let c = code[i];
        if c == b'#' && code.get(i + 1) == Some(&b'[') {
            let close = code[i..].iter().position(|&x| x == b']').map_or(code.len(), |p| i + p);
            test_item |= is_test_attribute(std::str::from_utf8(&code[i + 2..close]).unwrap_or(""));
            i = close;
        } else if test_item && c == b'{' {
            i = matching_brace(code, i);
            test_item = false;
        } else if c == b';' {
            test_item = false;
        } else if is_word(c) && (i == 0 || !is_word(code[i - 1])) {
            let word = word_at(i);
            let after = i + word.len();
            let next_word_at = after + code[after..].iter().take_while(|c| c.is_ascii_whitespace()).count();
            if word == "mod" && test_item && code.get(next_word_at).is_some_and(|&c| is_word(c)) {
                let name = word_at(next_word_at);
                let rest = &code[next_word_at + name.len()..];
                if rest.iter().find(|c| !c.is_ascii_whitespace()) == Some(&b';') {
                    result.test_modules.push(name.to_string());
                }
            }
            if word == "fn"
                && !test_item
                && code.get(next_word_at).is_some_and(|&c| is_word(c))
                && let Some(open) = body_start(code, next_word_at)
            {
                let close = matching_brace(code, open);
                result.functions.push(Function {
                    name: word_at(next_word_at).to_string(),
                    first_line: line_of(i),
                    last_line: line_of(close),
                });
            }
            i = after.max(i + 1) - 1;
        }
        i += 1;
    }
    result
}

/// The brace opening a function's body, or `None` for a declaration without one (a trait
/// method's `;`). Brackets and parentheses are skipped: `[u8; 4]` in a signature is no end.
fn body_start(code: &[u8], from: usize) -> Option<usize> {
    let mut depth = 0i64;
    for (k, &c) in code.iter().enumerate().skip(from) {
        match c {
            b'(' | b'[' => depth += 1,
            b')' | b']' => depth -= 1,
            b'{' if depth == 0 => return Some(k),
            b';' if depth == 0 => return None,
            _ => {}
        }
    }
    None
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable source directory") {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            if path.file_name().is_some_and(|n| n != "tests") {
                rust_files(&path, out);
            }
        } else if path.extension().is_some_and(|e| e == "rs") && path.file_name().is_some_and(|n| n != "tests.rs") {
            out.push(path);
        }
    }
}

/// The file a `mod name;` declared in `file` lives in: `name.rs` or `name/mod.rs` beside a
/// `mod.rs`/`lib.rs`/`main.rs`, else in the folder named after `file`.
fn module_files(file: &Path, name: &str) -> [PathBuf; 2] {
    let folder = match file.file_name().and_then(|n| n.to_str()) {
        Some("mod.rs" | "lib.rs" | "main.rs") => file.parent().expect("a folder").to_path_buf(),
        _ => file.with_extension(""),
    };
    [folder.join(format!("{name}.rs")), folder.join(name).join("mod.rs")]
}

/// Every library function of `src` with the file it is in, relative to `src`.
fn library_functions(src: &Path) -> Vec<(String, Function)> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files.sort();
    let scans: Vec<(PathBuf, Scan)> = files
        .into_iter()
        .map(|f| {
            let text = std::fs::read_to_string(&f).expect("readable source file");
            (f, scan(&text))
        })
        .collect();
    let test_files: BTreeSet<PathBuf> =
        scans.iter().flat_map(|(f, s)| s.test_modules.iter().flat_map(|m| module_files(f, m))).collect();
    scans
        .into_iter()
        .filter(|(f, _)| !test_files.contains(f))
        .flat_map(|(f, s)| {
            let relative = f.strip_prefix(src).expect("under src").to_string_lossy().replace('\\', "/");
            s.functions.into_iter().map(move |function| (relative.clone(), function))
        })
        .collect()
}

#[test]
fn no_library_function_is_longer_than_the_limit() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut functions = library_functions(&src);
    functions.sort_by(|a, b| b.1.lines().cmp(&a.1.lines()).then_with(|| a.0.cmp(&b.0)));
    println!("the ten longest functions:");
    for (file, f) in functions.iter().take(10) {
        println!("{:5} {file}:{} {}", f.lines(), f.first_line, f.name);
    }
    let too_long: Vec<String> = functions
        .iter()
        .filter(|(_, f)| f.lines() > LIMIT)
        .map(|(file, f)| format!("{file}:{} {} ({} lines)", f.first_line, f.name, f.lines()))
        .collect();
    assert!(too_long.is_empty(), "functions over {LIMIT} lines:\n{}", too_long.join("\n"));
}

#[cfg(test)]
mod scanner {
    use super::*;

    fn names_and_lines(src: &str) -> Vec<(String, usize)> {
        scan(src).functions.into_iter().map(|f| (f.name.clone(), f.lines())).collect()
    }

    #[test]
    fn a_brace_inside_a_string_is_not_code() {
        let src = "fn a() {\n    let s = \"}\";\n    let t = '{';\n}\nfn b() {}\n";
        assert_eq!(names_and_lines(src), [("a".to_string(), 4), ("b".to_string(), 1)]);
    }

    #[test]
    fn a_comment_marker_inside_a_string_is_followed_by_code() {
        let src = "fn a() {\n    let url = \"http://x\"; if true {\n    }\n}\n";
        assert_eq!(names_and_lines(src), [("a".to_string(), 4)]);
    }

    #[test]
    fn raw_strings_end_at_their_own_hashes() {
        let src = "fn a() {\n    let s = r#\"a \"} quoted\" {\"#;\n    let t = r\"}\\\";\n    let u = br##\"\"#}\"##;\n}\nfn b() {\n}\n";
        assert_eq!(names_and_lines(src), [("a".to_string(), 5), ("b".to_string(), 2)]);
    }

    #[test]
    fn comments_escapes_and_lifetimes_are_not_braces() {
        let src = "fn a<'x>(s: &'x str) -> &'x str {\n    // }\n    /* { /* } */ } */\n    let q = \"\\\"}\";\n    let c = '\\'';\n    s\n}\n";
        assert_eq!(names_and_lines(src), [("a".to_string(), 7)]);
    }

    #[test]
    fn a_nested_fn_is_counted_inside_its_outer_fn() {
        let src = "fn outer() {\n    fn inner() {\n        let _ = 1;\n    }\n    inner();\n}\n";
        assert_eq!(names_and_lines(src), [("outer".to_string(), 6), ("inner".to_string(), 3)]);
    }

    #[test]
    fn a_trait_method_without_a_body_is_no_function() {
        let src = "trait T {\n    fn a(&self, x: [u8; 4]);\n    fn b(&self) {\n    }\n}\nfn c(f: fn(u8) -> u8) {}\n";
        assert_eq!(names_and_lines(src), [("b".to_string(), 2), ("c".to_string(), 1)]);
    }

    #[test]
    fn test_code_is_left_out() {
        let src = "fn a() {}\n#[cfg(test)]\nmod tests {\n    fn helper() {}\n}\n#[test]\nfn check() {}\n#[cfg(test)]\nmod grids;\n#[cfg(not(test))]\nfn b() {}\n";
        let s = scan(src);
        let names: Vec<&str> = s.functions.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["a", "b"]);
        assert_eq!(s.test_modules, ["grids"]);
    }
}
