//! The modules' imports point one way: no file of `src/` imports, through `crate::`
//! paths, a file that imports it back. Test modules (everything after a file's first
//! `#[cfg(test)]`) are left out, as they may reach anywhere.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file below `dir`, keyed by its module path (`spec::load`, `data`).
fn modules(dir: &Path, prefix: &[String], found: &mut BTreeMap<Vec<String>, PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let mut module = prefix.to_vec();
        if path.is_dir() {
            module.push(name);
            modules(&path, &module, found);
        } else if path.extension().is_some_and(|e| e == "rs") {
            if !["mod", "lib", "main"].contains(&name.as_str()) {
                module.push(name);
            }
            found.insert(module, path);
        }
    }
}

/// The module paths a source text names after `crate::`, with `use crate::{a, b::c}`
/// groups opened one level: `a`, `b::c`.
fn imported_paths(text: &str) -> Vec<Vec<String>> {
    let ident = |s: &str| -> usize {
        s.find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(s.len())
    };
    let path_at = |s: &str| -> Vec<String> {
        let mut path = Vec::new();
        let mut rest = s;
        loop {
            let n = ident(rest);
            if n == 0 {
                break;
            }
            path.push(rest[..n].to_string());
            match rest[n..].strip_prefix("::") {
                Some(next) => rest = next,
                None => break,
            }
        }
        path
    };
    let mut paths = Vec::new();
    for (at, _) in text.match_indices("crate::") {
        let rest = &text[at + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 0;
            let mut start = 0;
            for (i, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        paths.push(path_at(group[start..i].trim()));
                        break;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        paths.push(path_at(group[start..i].trim()));
                        start = i + 1;
                    }
                    _ => {}
                }
            }
        } else {
            paths.push(path_at(rest));
        }
    }
    paths
}

/// Every source file's module path, with the module paths it imports, in other files.
fn imports() -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = BTreeMap::new();
    modules(&src, &[], &mut files);
    let resolve = |path: &[String]| {
        (1..=path.len())
            .rev()
            .find(|&n| files.contains_key(&path[..n]))
            .map(|n| path[..n].to_vec())
    };
    let mut imports = BTreeMap::new();
    for (module, file) in &files {
        let text = std::fs::read_to_string(file).unwrap();
        let code = text.split("#[cfg(test)]").next().unwrap();
        let targets = imported_paths(code)
            .iter()
            .filter_map(|path| resolve(path))
            .filter(|target| target != module)
            .collect();
        imports.insert(module.clone(), targets);
    }
    imports
}

#[test]
fn no_file_of_src_imports_one_that_imports_it_back() {
    let imports = imports();
    // A module reaches itself through others exactly when it is on a cycle.
    let mut cycles = Vec::new();
    for start in imports.keys() {
        let mut seen = BTreeSet::new();
        let mut stack: Vec<&Vec<String>> = imports[start].iter().collect();
        while let Some(module) = stack.pop() {
            if module == start {
                cycles.push(start.join("::"));
                break;
            }
            if seen.insert(module) {
                stack.extend(&imports[module]);
            }
        }
    }
    assert!(
        imports.len() > 30,
        "found only {} source files",
        imports.len()
    );
    assert!(
        cycles.is_empty(),
        "these modules import, through others, a module that imports them: {}",
        cycles.join(", ")
    );
}

/// lib.rs declares its modules in the order data flows through them, the leaves that
/// every stage shares first: a module may import only those declared before it.
#[test]
fn each_module_imports_only_those_lib_rs_declares_before_it() {
    let lib =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs")).unwrap();
    let order: Vec<String> = lib
        .lines()
        .filter_map(|line| line.strip_prefix("pub mod "))
        .map(|rest| rest.trim_end_matches(';').to_string())
        .collect();
    assert!(order.len() > 10, "lib.rs declares only {order:?}");
    let rank = |module: &[String]| {
        module
            .first()
            .and_then(|top| order.iter().position(|m| m == top))
    };
    let mut upward = Vec::new();
    for (module, targets) in imports() {
        let Some(from) = rank(&module) else { continue };
        for target in targets {
            if rank(&target).is_some_and(|to| to > from) {
                upward.push(format!(
                    "{} imports {}",
                    module.join("::"),
                    target.join("::")
                ));
            }
        }
    }
    assert!(
        upward.is_empty(),
        "these imports point against lib.rs's order:\n{}",
        upward.join("\n")
    );
}

#[test]
fn imported_paths_open_use_groups() {
    let text = "use crate::spec::{Spec, Dvl};\nuse crate::{files::write_atomic, vocab::{A, B}};\nlet x = crate::rng::task_rng(0);";
    let expected: Vec<Vec<String>> = [
        &["spec"][..],
        &["files", "write_atomic"],
        &["vocab"],
        &["rng", "task_rng"],
    ]
    .iter()
    .map(|path| path.iter().map(|s| s.to_string()).collect())
    .collect();
    assert_eq!(imported_paths(text), expected);
}
