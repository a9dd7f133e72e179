//! The crate's layering: no module of `src/` imports from a layer above its own.
//!
//! The layers are those of the crate documentation (`src/lib.rs`, "Layers"), lowest first;
//! [`LAYERS`] below is the same table. Every `src/**/*.rs` file belongs to the layer of its
//! top-level module (`src/<module>.rs` or `src/<module>/...`). The check strips comments
//! (doc links may point anywhere) and string literals, then reads every `crate::<module>`
//! path (in `use` declarations, `{...}` groups included, and in expressions and types) and
//! every `crate::<Item>` of an item the crate root re-exports (`pub use <module>::Item` in
//! `lib.rs`), and reports the file and the import when the module's layer is higher than the
//! file's. Same-layer imports are allowed. `src/lib.rs` itself assembles the crate and is not
//! checked.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

/// The layers, lowest first, each with its top-level modules.
const LAYERS: &[(&str, &[&str])] = &[
    (
        "foundations",
        &["error", "torus", "special", "seed", "progress", "partition"],
    ),
    ("target", &["target"]),
    ("tunable", &["tunable"]),
    ("proposal", &["proposal"]),
    ("kernel", &["kernel", "mh", "stats"]),
    ("controller", &["controller"]),
    ("kernel families", &["delayed_rejection", "langevin"]),
    ("chain", &["chain"]),
    ("render loop", &["render_loop"]),
    ("test support", &["testing", "toy"]),
];

/// One import from a higher layer.
#[derive(Debug, PartialEq, Eq)]
struct Violation {
    file: String,
    import: String,
    file_layer: &'static str,
    import_layer: &'static str,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} (layer `{}`) imports `{}` from the higher layer `{}`",
            self.file, self.file_layer, self.import, self.import_layer
        )
    }
}

/// The layer index and name of a top-level module.
fn layer_of_module(module: &str) -> Option<(usize, &'static str)> {
    LAYERS
        .iter()
        .enumerate()
        .find(|(_, (_, modules))| modules.contains(&module))
        .map(|(i, (name, _))| (i, *name))
}

/// The top-level module of a file, from its path relative to `src/` (`None` for `lib.rs`).
fn module_of_file(relative: &str) -> Option<String> {
    let relative = relative.replace('\\', "/");
    if relative == "lib.rs" {
        return None;
    }
    let first = relative.split('/').next().unwrap_or(&relative);
    Some(first.trim_end_matches(".rs").to_string())
}

/// The source with comments and the contents of string and character literals replaced by
/// spaces (newlines kept, so line numbers survive).
fn strip_comments_and_strings(source: &str) -> String {
    let chars: Vec<char> = source.chars().collect();
    let mut out = String::with_capacity(source.len());
    let blank = |c: char| if c == '\n' { '\n' } else { ' ' };
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                out.push(' ');
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    out.push(blank(chars[i]));
                    i += 1;
                }
            }
        } else if c == 'r'
            && (next == Some('"') || next == Some('#'))
            && (i == 0 || !is_ident(chars[i - 1]))
        {
            // A raw string r"..." or r#"..."#.
            let mut j = i + 1;
            let mut hashes = 0;
            while chars.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if chars.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            out.push_str(&" ".repeat(j + 1 - i));
            i = j + 1;
            while i < chars.len() {
                if chars[i] == '"' && (0..hashes).all(|h| chars.get(i + 1 + h) == Some(&'#')) {
                    out.push_str(&" ".repeat(1 + hashes));
                    i += 1 + hashes;
                    break;
                }
                out.push(blank(chars[i]));
                i += 1;
            }
        } else if c == '"' {
            out.push(' ');
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                if chars[i] == '\\' {
                    out.push(' ');
                    i += 1;
                }
                if i < chars.len() {
                    out.push(blank(chars[i]));
                    i += 1;
                }
            }
            out.push(' ');
            i += 1;
        } else if c == '\'' {
            // A character literal ('x', '\n', '\u{..}'), or a lifetime ('a), kept as is.
            if next == Some('\\') {
                let mut j = i + 2;
                while j < chars.len() && chars[j] != '\'' {
                    j += 1;
                }
                out.push_str(&" ".repeat(j + 1 - i));
                i = j + 1;
            } else if chars.get(i + 2) == Some(&'\'') {
                out.push_str("   ");
                i += 3;
            } else {
                out.push(c);
                i += 1;
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The leading identifier of `text` (after whitespace).
fn leading_ident(text: &str) -> &str {
    let text = text.trim_start();
    let end = text.find(|c: char| !is_ident(c)).unwrap_or(text.len());
    &text[..end]
}

/// The first path segments named after every `crate::` in `code` (comments already
/// stripped): `crate::a::B` gives `a`, `crate::{a::B, c}` gives `a` and `c`.
fn crate_paths(code: &str) -> Vec<String> {
    let mut found = Vec::new();
    let mut start = 0;
    while let Some(pos) = code[start..].find("crate::") {
        let at = start + pos;
        start = at + "crate::".len();
        if code[..at].chars().next_back().is_some_and(is_ident) {
            continue; // e.g. `mcmc_crate::` (`$crate::` is kept: `$` is no identifier)
        }
        let rest = code[start..].trim_start();
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 1;
            let mut item_start = 0;
            let mut items = Vec::new();
            for (k, ch) in group.char_indices() {
                match ch {
                    '{' => depth += 1,
                    '}' => {
                        depth -= 1;
                        if depth == 0 {
                            items.push(&group[item_start..k]);
                            break;
                        }
                    }
                    ',' if depth == 1 => {
                        items.push(&group[item_start..k]);
                        item_start = k + 1;
                    }
                    _ => {}
                }
            }
            found.extend(
                items
                    .into_iter()
                    .map(leading_ident)
                    .filter(|s| !s.is_empty())
                    .map(str::to_string),
            );
        } else {
            let ident = leading_ident(rest);
            if !ident.is_empty() {
                found.push(ident.to_string());
            }
        }
    }
    found
}

/// What the crate root exports under its own name: item -> defining top-level module, read
/// from `pub use <module>::...` in `lib.rs`; items `lib.rs` defines itself (`pub type`,
/// `pub fn`, ...) map to `"error"`'s layer, the foundations.
fn root_items(lib_rs: &str) -> BTreeMap<String, String> {
    let code = strip_comments_and_strings(lib_rs);
    let mut map = BTreeMap::new();
    for statement in code.split(';') {
        let statement = statement.trim();
        let Some(at) = statement.find("pub use ") else {
            for kind in [
                "pub type ",
                "pub fn ",
                "pub const ",
                "pub struct ",
                "pub enum ",
            ] {
                if let Some(k) = statement.find(kind) {
                    let name = leading_ident(&statement[k + kind.len()..]);
                    map.insert(name.to_string(), "error".to_string());
                }
            }
            continue;
        };
        let path = &statement[at + "pub use ".len()..];
        let module = leading_ident(path).to_string();
        if layer_of_module(&module).is_none() {
            continue; // `pub use rand;`: an external crate.
        }
        let tail = &path[module.len()..];
        for name in tail.split([',', '{', '}', ':']) {
            let name = name.trim();
            let name = name.rsplit(" as ").next().unwrap_or(name).trim();
            if !name.is_empty() && name.chars().all(is_ident) {
                map.insert(name.to_string(), module.clone());
            }
        }
    }
    map
}

/// The layering violations of one file: `relative` is its path below `src/`.
fn check_file(
    relative: &str,
    source: &str,
    root: &BTreeMap<String, String>,
) -> Result<Vec<Violation>, String> {
    let Some(module) = module_of_file(relative) else {
        return Ok(Vec::new());
    };
    let (file_index, file_layer) = layer_of_module(&module)
        .ok_or_else(|| format!("src/{relative}: module `{module}` is in no layer of LAYERS"))?;
    let mut violations = Vec::new();
    for first in crate_paths(&strip_comments_and_strings(source)) {
        let target = if layer_of_module(&first).is_some() {
            first.clone()
        } else if let Some(m) = root.get(&first) {
            m.clone()
        } else if first == "self" {
            continue;
        } else {
            return Err(format!(
                "src/{relative}: `crate::{first}` is neither a module of LAYERS nor an item \
                 re-exported by lib.rs"
            ));
        };
        let (index, layer) = layer_of_module(&target).expect("checked above");
        if index > file_index {
            violations.push(Violation {
                file: format!("src/{relative}"),
                import: format!("crate::{first}"),
                file_layer,
                import_layer: layer,
            });
        }
    }
    Ok(violations)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

fn src_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

#[test]
fn no_module_imports_from_a_higher_layer() {
    let src = src_dir();
    let root = root_items(&fs::read_to_string(src.join("lib.rs")).expect("lib.rs"));
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    assert!(files.len() > 20, "found only {} files", files.len());
    let mut problems = Vec::new();
    for path in &files {
        let relative = path
            .strip_prefix(&src)
            .expect("below src")
            .to_string_lossy();
        let source = fs::read_to_string(path).expect("readable source");
        match check_file(&relative, &source, &root) {
            Ok(v) => problems.extend(v.iter().map(ToString::to_string)),
            Err(e) => problems.push(e),
        }
    }
    assert!(
        problems.is_empty(),
        "layering violations:\n{}",
        problems.join("\n")
    );
}

/// Every top-level module of `src/` is in the table, and the table names no module that does
/// not exist (so the table and the crate cannot drift apart silently).
#[test]
fn the_table_covers_exactly_the_crates_modules() {
    let src = src_dir();
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut modules: Vec<String> = files
        .iter()
        .filter_map(|p| module_of_file(&p.strip_prefix(&src).ok()?.to_string_lossy()))
        .collect();
    modules.sort();
    modules.dedup();
    let mut table: Vec<String> = LAYERS
        .iter()
        .flat_map(|(_, m)| m.iter().map(|s| s.to_string()))
        .collect();
    table.sort();
    assert_eq!(modules, table);
}

/// Negative control: a synthetic file that imports upward is reported, naming the file and
/// the import, whatever the form of the path; comments and strings are ignored.
#[test]
fn the_checker_reports_an_upward_import() {
    let root = root_items("pub use chain::Chain;\npub use error::McmcError;\npub type Rng = u8;");
    let upward = "//! A proposal that reaches up.\n\
                  use crate::target::Target;\n\
                  use crate::render_loop::SharedController;\n\
                  use crate::{torus::wrap, chain::Chain as C};\n\
                  fn f() -> crate::Chain { panic!() }\n\
                  fn g() -> crate::McmcError { panic!() }\n";
    let v = check_file("proposal/fake.rs", upward, &root).unwrap();
    let imports: Vec<&str> = v.iter().map(|v| v.import.as_str()).collect();
    assert_eq!(
        imports,
        ["crate::render_loop", "crate::chain", "crate::Chain"]
    );
    assert!(v.iter().all(|v| v.file == "src/proposal/fake.rs"));
    let message = v[0].to_string();
    assert!(
        message.contains("src/proposal/fake.rs") && message.contains("crate::render_loop"),
        "{message}"
    );

    // Comments, doc links and strings do not count; same-layer and lower imports are fine.
    let clean = "/// See [`crate::render_loop::RenderLoop`].\n\
                 // use crate::chain::Chain;\n\
                 /* crate::testing:: */\n\
                 const S: &str = \"crate::toy::Banana\";\n\
                 const R: &str = r#\"crate::toy::\"#;\n\
                 fn lt<'a>(x: &'a str) -> char { let _ = x; '\"' }\n\
                 use crate::proposal::Proposal;\n\
                 use crate::partition::Partition;\n";
    assert_eq!(check_file("proposal/fake.rs", clean, &root).unwrap(), []);

    // A module missing from the table, or an unknown root item, is an error.
    assert!(check_file("newmodule.rs", "", &root).is_err());
    assert!(check_file("proposal/fake.rs", "use crate::Nowhere;", &root).is_err());
}
