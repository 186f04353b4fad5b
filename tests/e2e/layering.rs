//! One way down (issue 18): every module of the crate imports only modules below it in
//! [`LAYERS`], and no folder's files import each other in a circle.
//!
//! The test reads the source, not the compiled crate: every `crate::name` in code (comments
//! and doc comments skipped) counts as an import of `name`, and every `super::name` or
//! `crate::folder::name` inside a folder as an import of that sibling.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The crate's top-level modules, lowest first. A module may import only modules listed
/// before it; the order is written here once.
const LAYERS: &[&str] = &[
    "geom",        // numbers, primitives, poses and moves
    "mesh",        // triangle meshes, exact point–mesh distance, plane sections
    "cad",         // NURBS curves and surfaces, IGES, tessellation
    "sample",      // the bundled sample part
    "tool",        // cutters and tool assemblies
    "access",      // visibility maps (obvhs rays)
    "multires",    // remeshing, Loop subdivision, lifting wavelets
    "impeller",    // impeller recognition: axis, symmetry, hub, blades
    "offset",      // stock-to-leave shapes
    "stock",       // in-process material (tri-dexel) and its removal
    "contour",     // 2.5D contour paths
    "lathe",       // lens turning: compensated polar grids and spiral programs
    "rough",       // layer roughing down to an offset shape
    "feed",        // feeds from engagement (cutting-force model)
    "collide",     // tool bodies against part and table (parry3d)
    "orient",      // tool axes
    "path",        // finishing passes and linking
    "tool_choice", // which tool reaches where
    "verify",      // independent checks of paths and posted programs
    "post",        // machines and G-code
    "error",       // the crate's error type
    "job",         // jobs, operations and their runner
    "cli",         // the command line
];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .expect("read src")
        .map(|e| e.expect("dir entry").path())
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

/// The code of a file with comments removed (line comments, doc comments, block comments).
fn code_of(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut in_block = 0usize;
    for line in text.lines() {
        let mut rest = line;
        let mut kept = String::new();
        loop {
            if in_block > 0 {
                match rest.find("*/") {
                    Some(i) => {
                        in_block -= 1;
                        rest = &rest[i + 2..];
                    }
                    None => break,
                }
            } else {
                let line_comment = rest.find("//");
                let block = rest.find("/*");
                match (line_comment, block) {
                    (Some(l), b) if b.is_none_or(|b| l < b) => {
                        kept.push_str(&rest[..l]);
                        break;
                    }
                    (_, Some(b)) => {
                        kept.push_str(&rest[..b]);
                        in_block += 1;
                        rest = &rest[b + 2..];
                    }
                    _ => {
                        kept.push_str(rest);
                        break;
                    }
                }
            }
        }
        out.push_str(&kept);
        out.push('\n');
    }
    out
}

/// `code` without its `#[cfg(test)]` items (test modules may use any sibling's fixtures).
fn without_tests(code: &str) -> String {
    let mut out = String::new();
    let mut rest = code;
    while let Some(i) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..i]);
        let item = &rest[i..];
        // The item ends at `;` (`mod tests;`) or at the brace closing its first block.
        let (mut depth, mut end) = (0usize, item.len());
        for (k, c) in item.char_indices() {
            match c {
                ';' if depth == 0 => {
                    end = k + 1;
                    break;
                }
                '{' => depth += 1,
                '}' => {
                    depth = depth.saturating_sub(1);
                    if depth == 0 {
                        end = k + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        rest = &item[end..];
    }
    out.push_str(rest);
    out
}

/// Identifiers that follow `prefix` in `code` (`crate::` → the module named after it).
fn names_after<'a>(code: &'a str, prefix: &str) -> Vec<&'a str> {
    let mut names = Vec::new();
    let mut from = 0;
    while let Some(i) = code[from..].find(prefix) {
        let start = from + i;
        // `wavemill::crate::` cannot occur, but `foo_crate::` must not count.
        let preceded = code[..start]
            .chars()
            .next_back()
            .is_some_and(|c| c.is_alphanumeric() || c == '_');
        let rest = &code[start + prefix.len()..];
        let end = rest
            .find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(rest.len());
        if !preceded && end > 0 {
            names.push(&rest[..end]);
        }
        from = start + prefix.len();
    }
    names
}

/// Top-level module of a source file (`src/job/report.rs` → `job`), and its child module
/// inside that folder (`report`), if any.
fn module_of(src: &Path, file: &Path) -> Option<(String, Option<String>)> {
    let rel = file.strip_prefix(src).ok()?;
    let parts: Vec<String> = rel
        .components()
        .map(|c| {
            c.as_os_str()
                .to_string_lossy()
                .trim_end_matches(".rs")
                .to_string()
        })
        .collect();
    match parts.as_slice() {
        [one] if one == "lib" || one == "main" => None,
        [one] => Some((one.clone(), None)),
        [folder, child, ..] => Some((folder.clone(), (child != "mod").then(|| child.clone()))),
        [] => None,
    }
}

fn has_cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    // Depth-first search with colours; returns one cycle as a path.
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(node.to_string(), 1);
        stack.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            match state.get(next.as_str()).copied().unwrap_or(0) {
                1 => {
                    let at = stack.iter().position(|n| n == next).unwrap_or(0);
                    let mut cycle = stack[at..].to_vec();
                    cycle.push(next.clone());
                    return Some(cycle);
                }
                0 => {
                    if let Some(c) = visit(next, graph, state, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state.insert(node.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for node in graph.keys() {
        if state.get(node.as_str()).copied().unwrap_or(0) == 0 {
            let mut stack = Vec::new();
            if let Some(c) = visit(node, graph, &mut state, &mut stack) {
                return Some(c);
            }
        }
    }
    None
}

#[test]
fn modules_import_only_modules_below_them_and_no_folder_has_a_cycle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let rank = |m: &str| LAYERS.iter().position(|l| *l == m);
    let mut upward = Vec::new();
    let mut unlisted = BTreeSet::new();
    let mut folders: BTreeMap<String, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    for file in &files {
        let Some((module, child)) = module_of(&src, file) else {
            continue;
        };
        let code = code_of(&std::fs::read_to_string(file).expect("read source"));
        let Some(own) = rank(&module) else {
            unlisted.insert(module.clone());
            continue;
        };
        for name in names_after(&code, "crate::") {
            if name == module {
                continue;
            }
            match rank(name) {
                Some(r) if r < own => {}
                Some(_) => upward.push(format!(
                    "{}: {module} imports {name}, which is not below it",
                    file.strip_prefix(&src).unwrap_or(file).display()
                )),
                None => {
                    unlisted.insert(name.to_string());
                }
            }
        }
        // Sibling imports inside the folder, for the cycle check.
        if let Some(child) = child.filter(|c| c != "tests") {
            let code = without_tests(&code);
            let siblings = folders.entry(module.clone()).or_default();
            let edges = siblings.entry(child.clone()).or_default();
            let direct = file.parent().is_some_and(|p| p == src.join(&module));
            let mut targets: Vec<&str> = names_after(&code, &format!("crate::{module}::"));
            if direct {
                targets.extend(names_after(&code, "super::"));
            }
            for t in targets {
                if t != child {
                    edges.insert(t.to_string());
                }
            }
        }
    }
    assert!(
        unlisted.is_empty(),
        "modules missing from LAYERS (add each where it belongs): {unlisted:?}"
    );
    assert!(upward.is_empty(), "upward imports:\n{}", upward.join("\n"));
    for (folder, graph) in &folders {
        // Only edges between files of the folder count (super:: may also name items of mod.rs).
        let graph: BTreeMap<String, BTreeSet<String>> = graph
            .iter()
            .map(|(k, v)| {
                (
                    k.clone(),
                    v.iter()
                        .filter(|t| graph.contains_key(*t))
                        .cloned()
                        .collect(),
                )
            })
            .collect();
        if let Some(cycle) = has_cycle(&graph) {
            panic!("circular imports in src/{folder}/: {}", cycle.join(" → "));
        }
    }
}

/// The checker itself: a comment does not count, an upward name does, test code is set
/// aside for the cycle check, a cycle is found.
#[test]
fn the_checker_sees_imports_and_cycles() {
    let code = code_of(
        "use crate::geom::Point3; // crate::cli\n/* crate::job */ let x = crate::post::emit;",
    );
    assert_eq!(names_after(&code, "crate::"), vec!["geom", "post"]);
    let code = "use super::a;\n#[cfg(test)]\nmod tests {\n    use super::b;\n    fn f() {}\n}\nuse super::c;";
    assert_eq!(names_after(&without_tests(code), "super::"), vec!["a", "c"]);
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    graph
        .entry("report".into())
        .or_default()
        .insert("semi_finish".into());
    assert!(has_cycle(&graph).is_none());
    graph
        .entry("semi_finish".into())
        .or_default()
        .insert("report".into());
    assert!(has_cycle(&graph).is_some());
}

/// Lines of `text` (a source file) whose code, comments and `#[cfg(test)]` items aside,
/// holds a `--flag`: in code that can only be inside a string.
fn flag_lines(text: &str) -> Vec<String> {
    without_tests(&code_of(text))
        .lines()
        .filter(|line| {
            let bytes = line.as_bytes();
            (2..bytes.len()).any(|i| {
                bytes[i - 2] == b'-'
                    && bytes[i - 1] == b'-'
                    && bytes[i].is_ascii_lowercase()
                    && (i < 3 || bytes[i - 3] != b'-')
            })
        })
        .map(|line| line.trim().to_string())
        .collect()
}

/// The library speaks in its own option and job-file names; only the CLI knows its flags
/// (`cli::name_flags` maps one to the other). A `--flag` in library code (comments and tests
/// aside) is a message that will be wrong for a library caller.
#[test]
fn the_library_names_no_command_line_flag() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut found = Vec::new();
    for file in &files {
        let relative = file.strip_prefix(&src).expect("under src");
        if relative.starts_with("cli") || relative == Path::new("main.rs") {
            continue;
        }
        for line in flag_lines(&std::fs::read_to_string(file).expect("read")) {
            found.push(format!("{}: {line}", relative.display()));
        }
    }
    assert!(
        found.is_empty(),
        "flag names in the library:\n{}",
        found.join("\n")
    );
    // The checker sees a flag in a string, and not in comments, tests or a `---` rule.
    let sample = "/// run with --tool\nlet m = \"give --tool flat:6\";\n// --z\nlet r = \"---x\";\n#[cfg(test)]\nmod tests {\n    const F: &str = \"--units\";\n}\n";
    assert_eq!(flag_lines(sample), ["let m = \"give --tool flat:6\";"]);
}
