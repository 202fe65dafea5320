//! The modules' imports point one way: no file of `src/` imports, through `crate::`,
//! `self::` or `super::` paths (`super::super::` too), or through a path that starts
//! with the bare name of a child module it declares (`mod figures;`, then
//! `figures::all(..)` or `use figures::{a, b}`), a file that imports it back, directly
//! or through others; a cycle fails the test, which names the files on it. A child
//! importing from its own ancestor (`super::Thing` from the parent's `mod.rs`) while
//! the parent calls the child is the usual shape of a Rust module, not a cycle.
//! Relative paths resolve from the file's own module, so `super::` in `plots/mod.rs`
//! means `report`, in `plots/draw.rs` it means `report::plots`. Test modules
//! (everything after a file's first `#[cfg(test)]`) are left out, as they may reach
//! anywhere. `python3 ../shared/tools/import_cycles.py .` reads the imports the same way.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Module = Vec<String>;

/// Every `.rs` file below `dir`, keyed by its module path (`spec::load`, `data`); the
/// crate root `lib.rs` is the empty path. `main.rs` is the binary, another crate.
fn modules(dir: &Path, prefix: &[String], found: &mut BTreeMap<Module, PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let mut module = prefix.to_vec();
        if path.is_dir() {
            module.push(name);
            modules(&path, &module, found);
        } else if path.extension().is_some_and(|e| e == "rs") {
            if prefix.is_empty() && name == "main" {
                continue;
            }
            if !["mod", "lib"].contains(&name.as_str()) {
                module.push(name);
            }
            found.insert(module, path);
        }
    }
}

fn ident_len(s: &str) -> usize {
    s.find(|c: char| !(c.is_alphanumeric() || c == '_'))
        .unwrap_or(s.len())
}

/// The `a::b::c` path at the start of `s`, ended by anything but an identifier and `::`,
/// and what follows its last identifier.
fn path_at(s: &str) -> (Module, &str) {
    let mut path = Vec::new();
    let mut rest = s;
    loop {
        let n = ident_len(rest);
        if n == 0 {
            break;
        }
        path.push(rest[..n].to_string());
        rest = &rest[n..];
        match rest.strip_prefix("::") {
            Some(next) if ident_len(next) > 0 => rest = next,
            _ => break,
        }
    }
    (path, rest)
}

/// The items of the `{..}` group that `group` starts just after, split at its top-level
/// commas: `a, b::c, d::{e, f}` gives `a`, `b::c`, `d::{e, f}`.
fn group_items(group: &str) -> Vec<&str> {
    let mut items = Vec::new();
    let mut depth = 0;
    let mut start = 0;
    for (i, c) in group.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => {
                items.push(group[start..i].trim());
                break;
            }
            '}' => depth -= 1,
            ',' if depth == 0 => {
                items.push(group[start..i].trim());
                start = i + 1;
            }
            _ => {}
        }
    }
    items
}

/// The child modules that `text` declares in files of their own: `mod figures;`,
/// `pub(crate) mod terms;`.
fn declared_children(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|line| {
            let line = line.trim_start();
            let line = match line.strip_prefix("pub") {
                Some(rest) if rest.starts_with('(') => rest[rest.find(')')? + 1..].trim_start(),
                Some(rest) if rest.starts_with(' ') => rest.trim_start(),
                _ => line,
            };
            let name = line.strip_prefix("mod ")?.trim_start();
            let n = ident_len(name);
            (n > 0 && name[n..].trim_start().starts_with(';')).then(|| name[..n].to_string())
        })
        .collect()
}

/// Where a path that starts at `rest` begins, and what follows its head: `crate::`,
/// `self::` and `super::` after anything but an identifier's character, a declared
/// child's bare name followed by `::` after anything but that, `::` or `.`; none when
/// no path starts there.
fn path_head<'t>(
    module: &[String],
    children: &[String],
    before: Option<char>,
    rest: &'t str,
) -> Option<(Module, &'t str)> {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    if before.is_some_and(ident) {
        return None;
    }
    for (head, base) in [
        ("crate::", Vec::new()),
        ("self::", module.to_vec()),
        ("super::", module[..module.len().saturating_sub(1)].to_vec()),
    ] {
        if let Some(after) = rest.strip_prefix(head) {
            return Some((base, after));
        }
    }
    if before.is_some_and(|c| c == ':' || c == '.') {
        return None;
    }
    children.iter().find_map(|child| {
        let after = rest.strip_prefix(child.as_str())?.strip_prefix("::")?;
        Some(([module, &[child.clone()]].concat(), after))
    })
}

/// The absolute module paths that the source text of `module` names after `crate::`,
/// `self::` and `super::` (any number of them), or after the bare name of a child
/// module it declares, with `use ...::{a, b::c}` groups opened one level: `a`, `b::c`.
fn imported_paths(module: &[String], text: &str) -> Vec<Module> {
    let children = declared_children(text);
    let mut paths = Vec::new();
    let mut at = 0;
    while at < text.len() {
        let rest = &text[at..];
        let before = text[..at].chars().next_back();
        let Some((mut base, mut rest)) = path_head(module, &children, before, rest) else {
            at += rest.chars().next().map_or(1, char::len_utf8);
            continue;
        };
        while let Some(next) = rest.strip_prefix("super::") {
            base.pop();
            rest = next;
        }
        // `head::a::b`, `head::{..}` or `head::a::{..}`.
        let (path, after) = path_at(rest);
        let named = !path.is_empty();
        let base = [base, path].concat();
        let group = if named {
            paths.push(base.clone());
            after.strip_prefix("::{")
        } else {
            rest.strip_prefix('{')
        };
        for item in group.map(group_items).unwrap_or_default() {
            let (path, _) = path_at(item);
            if !path.is_empty() && path != ["self"] {
                paths.push([base.clone(), path].concat());
            }
        }
        at = text.len() - rest.len();
    }
    paths
}

/// Every source file's module path, with the module paths it imports, in other files.
fn imports() -> BTreeMap<Module, BTreeSet<Module>> {
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
        let targets = imported_paths(module, code)
            .iter()
            .filter_map(|path| resolve(path))
            .filter(|target| target != module)
            .collect();
        imports.insert(module.clone(), targets);
    }
    imports
}

/// The groups of two or more modules that import each other, directly or through
/// others (the strongly connected components of the import graph), each sorted.
fn cycles(imports: &BTreeMap<Module, BTreeSet<Module>>) -> BTreeSet<BTreeSet<Module>> {
    let reach = |start: &Module| {
        let mut seen = BTreeSet::new();
        let mut stack: Vec<&Module> = imports.get(start).into_iter().flatten().collect();
        while let Some(module) = stack.pop() {
            if seen.insert(module.clone()) {
                stack.extend(imports.get(module).into_iter().flatten());
            }
        }
        seen
    };
    let reaches: BTreeMap<&Module, BTreeSet<Module>> =
        imports.keys().map(|m| (m, reach(m))).collect();
    reaches
        .iter()
        .filter(|(module, reached)| reached.contains(**module))
        .map(|(module, reached)| {
            reached
                .iter()
                .filter(|other| reaches.get(other).is_some_and(|r| r.contains(*module)))
                .cloned()
                .collect()
        })
        .collect()
}

/// A module's file as the cycle report names it: `report/plots/draw.rs`.
fn file_of(module: &Module, files: &BTreeMap<Module, BTreeSet<Module>>) -> String {
    let is_folder = files
        .keys()
        .any(|other| other.len() > module.len() && other.starts_with(module));
    match (module.is_empty(), is_folder) {
        (true, _) => "lib.rs".to_string(),
        (false, true) => format!("{}/mod.rs", module.join("/")),
        (false, false) => format!("{}.rs", module.join("/")),
    }
}

/// `imports` without those from a module's own ancestor (`super::Thing` in a child of
/// the module that declares it): the usual shape of a Rust module, not a cycle.
fn without_ancestor_imports(
    imports: &BTreeMap<Module, BTreeSet<Module>>,
) -> BTreeMap<Module, BTreeSet<Module>> {
    imports
        .iter()
        .map(|(module, targets)| {
            let downward = targets
                .iter()
                .filter(|t| !(t.len() < module.len() && module.starts_with(t)))
                .cloned()
                .collect();
            (module.clone(), downward)
        })
        .collect()
}

#[test]
fn no_file_of_src_imports_one_that_imports_it_back() {
    let imports = imports();
    assert!(
        imports.len() > 30,
        "found only {} source files",
        imports.len()
    );
    assert!(
        imports.values().map(BTreeSet::len).sum::<usize>() > 150,
        "found only a few imports: {imports:?}"
    );
    let found: Vec<String> = cycles(&without_ancestor_imports(&imports))
        .iter()
        .map(|cycle| {
            let files: Vec<String> = cycle.iter().map(|m| file_of(m, &imports)).collect();
            format!("cycle of {} files: {}", files.len(), files.join(", "))
        })
        .collect();
    assert!(
        found.is_empty(),
        "these files of src/ import, directly or through others, a file that imports them:\n{}",
        found.join("\n")
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

fn modules_of(paths: &[&[&str]]) -> Vec<Module> {
    paths
        .iter()
        .map(|path| path.iter().map(|s| s.to_string()).collect())
        .collect()
}

#[test]
fn imported_paths_open_use_groups() {
    let text = "use crate::spec::{Spec, Dvl};\nuse crate::{files::write_atomic, vocab::{A, B}};\nlet x = crate::rng::task_rng(0);";
    let expected = modules_of(&[
        &["spec"],
        &["spec", "Spec"],
        &["spec", "Dvl"],
        &["files", "write_atomic"],
        &["vocab"],
        &["rng", "task_rng"],
    ]);
    assert_eq!(imported_paths(&[], text), expected);
}

/// `super::` and `self::` start from the file's module: a `mod.rs` file is its folder's
/// module, so its `super::` is the folder's parent; any other file's is its folder.
#[test]
fn imported_paths_resolve_self_and_super_from_the_files_module() {
    let text = "use super::scale::Scale;\nuse self::inner::X;\nuse super::super::{results::read, self, vocab::{A, B}};\nlet t = super::draw::three_digits(1.0);\nlet s = Self::new(); let m = myself::x; let y = $crate::vocab::Z;";
    // report/plots/draw.rs
    let draw = ["report", "plots", "draw"].map(String::from);
    assert_eq!(
        imported_paths(&draw, text),
        modules_of(&[
            &["report", "plots", "scale", "Scale"],
            &["report", "plots", "draw", "inner", "X"],
            &["report", "results", "read"],
            &["report", "vocab"],
            &["report", "plots", "draw", "three_digits"],
            &["vocab", "Z"],
        ])
    );
    // report/plots/mod.rs
    let plots = ["report", "plots"].map(String::from);
    assert_eq!(
        imported_paths(&plots, text),
        modules_of(&[
            &["report", "scale", "Scale"],
            &["report", "plots", "inner", "X"],
            &["results", "read"],
            &["vocab"],
            &["report", "draw", "three_digits"],
            &["vocab", "Z"],
        ])
    );
}

/// A parent calls its children by their bare names, in `use` groups and in code; a
/// path through another module's child of the same name, or after a `.`, is not one.
#[test]
fn imported_paths_follow_a_declared_childs_bare_name() {
    let text = "pub mod figures;\npub(crate) mod terms;\nmod inline { }\npub use figures::{draw_all, draw_sweep};\nlet t = terms::readable(x);\nlet o = crate::other::terms::q; let v = value.terms::w; let i = inline::z;";
    let installation = ["report", "installation"].map(String::from);
    assert_eq!(
        imported_paths(&installation, text),
        modules_of(&[
            &["report", "installation", "figures", "draw_all"],
            &["report", "installation", "figures", "draw_sweep"],
            &["report", "installation", "terms", "readable"],
            &["other", "terms", "q"],
        ])
    );
}

/// A child importing from its parent, which calls it, is no cycle; two siblings
/// reaching each other through their parent's calls are.
#[test]
fn an_import_from_an_ancestor_is_not_a_cycle_but_one_between_cousins_is() {
    let module = |path: &str| -> Module { path.split("::").map(String::from).collect() };
    let graph: BTreeMap<Module, BTreeSet<Module>> = [
        ("report", &["report::plots"][..]),
        ("report::plots", &["report", "report::plots::figures"]),
        (
            "report::plots::figures",
            &["report::plots", "report::installation"],
        ),
        ("report::installation", &["report", "report::plots"]),
    ]
    .into_iter()
    .map(|(from, to)| (module(from), to.iter().map(|t| module(t)).collect()))
    .collect();
    let found: Vec<Vec<String>> = cycles(&without_ancestor_imports(&graph))
        .iter()
        .map(|cycle| cycle.iter().map(|m| m.join("::")).collect())
        .collect();
    assert_eq!(
        found,
        [vec![
            "report::installation",
            "report::plots",
            "report::plots::figures"
        ]]
    );
}

#[test]
fn cycles_are_the_groups_that_reach_each_other() {
    let graph: BTreeMap<Module, BTreeSet<Module>> = [
        ("a", &["b"][..]),
        ("b", &["a", "c"]),
        ("c", &["d"]),
        ("d", &["e"]),
        ("e", &["c"]),
        ("f", &["a"]),
    ]
    .into_iter()
    .map(|(from, to)| {
        (
            vec![from.to_string()],
            to.iter().map(|t| vec![t.to_string()]).collect(),
        )
    })
    .collect();
    let found: Vec<Vec<String>> = cycles(&graph)
        .iter()
        .map(|cycle| cycle.iter().map(|m| m.join("::")).collect())
        .collect();
    assert_eq!(found, [vec!["a", "b"], vec!["c", "d", "e"]]);
}
