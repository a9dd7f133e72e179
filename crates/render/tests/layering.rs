//! The module graph of `render` has no cycle and no module imports from a layer above its
//! own (the layers of the crate documentation): read from the sources, every `crate::<module>`
//! path of a top-level module is an edge. Negative controls: a synthetic upward import and a
//! synthetic cycle are reported.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The layers, lowest first (`render/src/lib.rs`): a module may import its own layer and the
/// ones below.
const LAYERS: &[&[&str]] = &[
    // foundations
    &[
        "autodiff",
        "budget",
        "error",
        "film",
        "frame",
        "image",
        "image_io",
        "metrics",
        "sampler",
        "warp",
        "test_util",
        "files",
        "shard",
    ],
    // scene
    &[
        "mesh",
        "bvh",
        "material",
        "camera",
        "light",
        "scene",
        "bundled",
        "pathspace_scene",
    ],
    // integrators and their drivers
    &["bdpt", "integrator", "mlt"],
    // methods: settings, presets, render functions, the table
    &["methods"],
    // entry point
    &["session"],
];

type Graph = BTreeMap<String, BTreeSet<String>>;

/// The top-level module a source file belongs to (`scene/gltf_load.rs` -> `scene`).
fn module_of(relative: &Path) -> String {
    let first = relative.components().next().unwrap();
    first
        .as_os_str()
        .to_string_lossy()
        .trim_end_matches(".rs")
        .to_owned()
}

/// The top-level modules named by `crate::` paths in `source` (comments skipped).
fn imports(source: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for line in source.lines() {
        let code = line.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(i) = rest.find("crate::") {
            rest = &rest[i + "crate::".len()..];
            if let Some(list) = rest.strip_prefix('{') {
                let end = list.find('}').unwrap_or(list.len());
                for item in list[..end].split(',') {
                    let name: String = item
                        .trim()
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    if !name.is_empty() {
                        out.insert(name);
                    }
                }
            } else {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.insert(name);
                }
            }
        }
    }
    out
}

fn graph_of(dir: &Path) -> Graph {
    let mut graph = Graph::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let module = module_of(path.strip_prefix(dir).unwrap());
                if module == "lib" {
                    continue;
                }
                let source = std::fs::read_to_string(&path).unwrap();
                let targets = graph.entry(module.clone()).or_default();
                targets.extend(imports(&source).into_iter().filter(|t| *t != module));
            }
        }
    }
    graph
}

fn layer(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

/// Every import from a higher layer, as "module -> target".
fn upward(graph: &Graph) -> Vec<String> {
    let mut bad = Vec::new();
    for (module, targets) in graph {
        let own = layer(module).unwrap_or_else(|| panic!("module {module} has no layer"));
        for t in targets {
            if layer(t).is_some_and(|l| l > own) {
                bad.push(format!("{module} -> {t}"));
            }
        }
    }
    bad
}

/// A cycle of the graph, if any (depth-first search).
fn cycle(graph: &Graph) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &Graph,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        match state.get(node) {
            Some(2) => return None,
            Some(1) => {
                let start = path.iter().position(|n| n == node).unwrap();
                let mut c = path[start..].to_vec();
                c.push(node.to_owned());
                return Some(c);
            }
            _ => {}
        }
        state.insert(node.to_owned(), 1);
        path.push(node.to_owned());
        for next in graph.get(node).into_iter().flatten() {
            if let Some(c) = visit(next, graph, state, path) {
                return Some(c);
            }
        }
        path.pop();
        state.insert(node.to_owned(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for node in graph.keys() {
        if let Some(c) = visit(node, graph, &mut state, &mut Vec::new()) {
            return Some(c);
        }
    }
    None
}

#[test]
fn render_modules_form_layers_without_cycles() {
    let graph = graph_of(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    assert!(graph.len() > 10, "too few modules read: {graph:?}");
    assert!(graph["session"].contains("methods"), "{graph:?}");
    assert_eq!(upward(&graph), Vec::<String>::new(), "imports back up");
    assert_eq!(cycle(&graph), None, "module cycle");
}

#[test]
fn upward_imports_and_cycles_are_reported() {
    let mut graph = graph_of(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    // An integrator reaching up into the session (the old cycle through the session's
    // settings) is both an upward import and, with the session's own imports, a cycle.
    graph.get_mut("mlt").unwrap().insert("session".to_owned());
    assert_eq!(upward(&graph), vec!["mlt -> session".to_owned()]);
    let mut cyclic = Graph::new();
    cyclic.insert("a".into(), ["b".to_owned()].into());
    cyclic.insert("b".into(), ["a".to_owned()].into());
    assert!(cycle(&cyclic).is_some());
    // The parser sees grouped and nested paths, not comments.
    let seen =
        imports("use crate::{scene::Scene, film};\n// crate::session\nlet x = crate::mlt::X;");
    assert_eq!(
        seen,
        ["film", "mlt", "scene"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    );
}
