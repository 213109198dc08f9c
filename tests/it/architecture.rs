//! ARCHITECTURE.md's module graph stays true: takes every top-level module under src/ and the
//! `crate::…` / `lapclone::…` paths its code names (comments left out), and gives the
//! modules each imports, which must equal the block under "## Module graph".

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Graph = BTreeMap<String, BTreeSet<String>>;

fn src() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The top-level modules: every file and folder of src/ but the crate roots.
fn modules() -> BTreeSet<String> {
    std::fs::read_dir(src())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter_map(|p| Some(p.file_stem()?.to_str()?.to_string()))
        .filter(|name| name != "lib" && name != "main")
        .collect()
}

fn rust_files(path: &Path, out: &mut Vec<PathBuf>) {
    if path.is_dir() {
        for entry in std::fs::read_dir(path).unwrap() {
            rust_files(&entry.unwrap().path(), out);
        }
    } else if path.is_file() && path.extension().is_some_and(|e| e == "rs") {
        out.push(path.to_path_buf());
    }
}

/// The other top-level modules that `text` names as `crate::m` or `lapclone::m`.
fn named_modules(text: &str, modules: &BTreeSet<String>) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    for line in text.lines().filter(|l| !l.trim_start().starts_with("//")) {
        for prefix in ["crate::", "lapclone::"] {
            for (at, _) in line.match_indices(prefix) {
                let preceded = line[..at].chars().last();
                if preceded.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                    continue;
                }
                let rest = &line[at + prefix.len()..];
                assert!(
                    !rest.starts_with('{'),
                    "write `{prefix}module::…` per module, not a group: {line}"
                );
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if modules.contains(&name) {
                    found.insert(name);
                }
            }
        }
    }
    found
}

fn graph_of_the_code() -> Graph {
    let modules = modules();
    let mut graph = Graph::new();
    for module in &modules {
        let mut files = Vec::new();
        let folder = src().join(module);
        rust_files(&folder, &mut files);
        rust_files(&src().join(format!("{module}.rs")), &mut files);
        let mut imports = BTreeSet::new();
        for file in files {
            imports.extend(named_modules(
                &std::fs::read_to_string(file).unwrap(),
                &modules,
            ));
        }
        imports.remove(module);
        graph.insert(module.clone(), imports);
    }
    graph
}

/// The block under "## Module graph": `name → a, b, c   (comment)` per line; modules it does
/// not list import nothing.
fn graph_of_the_document() -> Graph {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("ARCHITECTURE.md");
    let text = std::fs::read_to_string(path).unwrap();
    let section = text
        .split("## Module graph")
        .nth(1)
        .expect("a module graph section");
    let block = section
        .split("```text\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("a ```text block");
    let mut graph: Graph = modules()
        .into_iter()
        .map(|m| (m, BTreeSet::new()))
        .collect();
    for line in block.lines().filter(|l| !l.trim().is_empty()) {
        let (name, imports) = line.split_once('→').expect("`module → imports`");
        let imports = imports.split('(').next().unwrap();
        let set = imports.split(',').map(|m| m.trim().to_string()).collect();
        graph.insert(name.trim().to_string(), set);
    }
    graph
}

#[test]
fn the_documented_module_graph_is_the_code_s() {
    let (code, document) = (graph_of_the_code(), graph_of_the_document());
    assert!(code.len() >= 15, "found the modules: {:?}", code.keys());
    for (module, imports) in &code {
        assert_eq!(
            Some(imports),
            document.get(module),
            "ARCHITECTURE.md's line for `{module}` (the code imports the left side)"
        );
    }
    assert_eq!(
        code.len(),
        document.len(),
        "modules ARCHITECTURE.md names but src/ lacks"
    );
}

#[test]
fn module_names_are_read_from_code_not_comments_or_longer_names() {
    let modules: BTreeSet<String> = ["mesh", "util", "pixels"].map(String::from).into();
    let text = "use crate::mesh::Mesh;\n// crate::util is only mentioned\n\
                let x = lapclone::pixels::Canvas::new(); my_crate::util::f();\n\
                use crate::mesh_extra::X;";
    let found = named_modules(text, &modules);
    assert_eq!(found, ["mesh", "pixels"].map(String::from).into());
}
