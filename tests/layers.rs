//! The crate's modules form layers (docs/architecture.md): a module uses only modules below it, so
//! each can be read, tested and replaced without the ones above. This test reads the sources and
//! fails on a cycle between the top-level modules (`crate::scene` using `crate::render` while
//! `render` uses `scene`), on a cycle between the files of one module (`render/bindings.rs` and
//! `render/chunks.rs` using each other), and on `ash` used outside `src/gpu/`. Unit tests
//! (`#[cfg(test)] mod tests`) may reach any layer and are not read.

mod common;

use common::rust_files;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A source file's code without its unit tests and comments.
fn code_of(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let without_tests = match text.find("#[cfg(test)]\nmod tests") {
        Some(at) => &text[..at],
        None => &text[..],
    };
    without_tests.lines().map(|l| l.split("//").next().unwrap_or("")).collect::<Vec<_>>().join("\n")
}

/// The identifiers that follow each occurrence of `prefix` in `code`.
fn names_after<'a>(code: &'a str, prefix: &'a str) -> impl Iterator<Item = &'a str> + 'a {
    code.match_indices(prefix).filter_map(move |(at, _)| {
        let rest = &code[at + prefix.len()..];
        let end = rest.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(rest.len());
        (end > 0).then(|| &rest[..end])
    })
}

/// A cycle in `graph`, as its nodes in order, if there is one.
fn find_cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|n| n == node) {
            let mut cycle = path[at..].to_vec();
            cycle.push(node.to_owned());
            return Some(cycle);
        }
        if done.contains(node) {
            return None;
        }
        path.push(node.to_owned());
        for next in graph.get(node).into_iter().flatten() {
            if let Some(cycle) = visit(next, graph, path, done) {
                return Some(cycle);
            }
        }
        path.pop();
        done.insert(node.to_owned());
        None
    }
    let mut done = BTreeSet::new();
    graph.keys().find_map(|node| visit(node, graph, &mut Vec::new(), &mut done))
}

struct Crate {
    root: PathBuf,
    files: Vec<PathBuf>,
}

impl Crate {
    fn read() -> Self {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut files = Vec::new();
        rust_files(&root, &mut files);
        files.retain(|f| !f.ends_with("main.rs") && !f.ends_with("lib.rs"));
        files.sort();
        Crate { root, files }
    }

    /// The path of `file` under src/, as module names: `render/chunks.rs` is ["render", "chunks"].
    fn module_path(&self, file: &Path) -> Vec<String> {
        let relative = file.strip_prefix(&self.root).unwrap().with_extension("");
        let mut names: Vec<String> = relative.iter().map(|c| c.to_string_lossy().into_owned()).collect();
        if names.last().is_some_and(|n| n == "mod") {
            names.pop();
        }
        names
    }

    fn top_level_modules(&self) -> BTreeSet<String> {
        self.files.iter().map(|f| self.module_path(f)[0].clone()).collect()
    }
}

#[test]
fn top_level_modules_form_layers() {
    let krate = Crate::read();
    let modules = krate.top_level_modules();
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for file in &krate.files {
        let own = krate.module_path(file)[0].clone();
        let code = code_of(file);
        let uses = graph.entry(own.clone()).or_default();
        for name in names_after(&code, "crate::") {
            if modules.contains(name) && name != own {
                uses.insert(name.to_owned());
            }
        }
    }
    assert!(graph.len() >= 8, "found only {:?}: the sources moved?", graph.keys());
    assert!(graph["render"].contains("gpu") && graph["render"].contains("scene"), "the reader misses uses: {graph:?}");
    if let Some(cycle) = find_cycle(&graph) {
        panic!("top-level modules use each other: {}", cycle.join(" -> "));
    }
}

#[test]
fn files_of_a_module_form_layers() {
    let krate = Crate::read();
    // Per directory: its files (a module's mod.rs is its face, which declares and re-exports the
    // others, so it is not one of the layers) and which of them each one uses.
    let mut graphs: BTreeMap<String, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    for file in &krate.files {
        let path = krate.module_path(file);
        if path.len() < 2 || file.ends_with("mod.rs") {
            continue;
        }
        let (dir, own) = (path[..path.len() - 1].join("/"), path[path.len() - 1].clone());
        graphs.entry(dir).or_default().entry(own).or_default();
    }
    for file in &krate.files {
        let path = krate.module_path(file);
        if path.len() < 2 || file.ends_with("mod.rs") {
            continue;
        }
        let (dir, own) = (path[..path.len() - 1].join("/"), path[path.len() - 1].clone());
        let code = code_of(file);
        let siblings: BTreeSet<String> = graphs[&dir].keys().cloned().collect();
        let crate_prefix = format!("crate::{}::", dir.replace('/', "::"));
        let used: BTreeSet<String> = names_after(&code, "super::")
            .chain(names_after(&code, &crate_prefix))
            .filter(|name| siblings.contains(*name) && **name != own)
            .map(str::to_owned)
            .collect();
        graphs.get_mut(&dir).unwrap().get_mut(&own).unwrap().extend(used);
    }
    assert!(graphs["render"]["renderer"].contains("bindings"), "the reader misses uses: {:?}", graphs["render"]);
    let cycles: Vec<String> = graphs
        .iter()
        .filter_map(|(dir, graph)| find_cycle(graph).map(|c| format!("src/{dir}: {}", c.join(" -> "))))
        .collect();
    assert!(cycles.is_empty(), "files of a module use each other:\n{}", cycles.join("\n"));
}

#[test]
fn only_the_gpu_module_touches_vulkan() {
    let krate = Crate::read();
    let outside: Vec<String> = krate
        .files
        .iter()
        .filter(|f| krate.module_path(f)[0] != "gpu")
        .filter(|f| {
            let code = code_of(f);
            code.contains("ash::") || code.contains("use ash") || code.contains("vk::")
        })
        .map(|f| f.strip_prefix(&krate.root).unwrap().display().to_string())
        .collect();
    assert!(outside.is_empty(), "Vulkan (ash) used outside src/gpu/: {outside:?}");
}

#[test]
fn the_cycle_finder_finds_cycles() {
    let graph = |edges: &[(&str, &str)]| {
        let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (a, b) in edges {
            g.entry(a.to_string()).or_default().insert(b.to_string());
            g.entry(b.to_string()).or_default();
        }
        g
    };
    assert_eq!(find_cycle(&graph(&[("a", "b"), ("b", "c"), ("a", "c")])), None);
    assert_eq!(find_cycle(&graph(&[("a", "b"), ("b", "c"), ("c", "a")])).map(|c| c.len()), Some(4));
    assert!(find_cycle(&graph(&[("x", "y"), ("y", "y")])).is_some());
}
