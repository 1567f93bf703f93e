//! The source layout keeps its two promises: no import cycles among the files of a folder (a
//! file uses its siblings through `super::name`; the folder's `mod.rs` only assembles them),
//! and the geometry core is engine-free (only `src/ecs/` names a `bevy_*` crate).
use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// The code of a source file without comments and without its test module (tests may use
/// anything).
fn code_lines(path: &Path) -> Vec<String> {
    let text = fs::read_to_string(path).expect("a readable source file");
    let code = text
        .split("#[cfg(test)]\nmod tests")
        .next()
        .unwrap_or_default();
    code.lines()
        .map(str::trim)
        .filter(|l| !l.starts_with("//"))
        .map(|l| l.split(" //").next().unwrap_or_default().to_string())
        .collect()
}

/// Every folder under `dir` with its `.rs` files (by module name, `mod` excluded).
fn folders(dir: &Path, out: &mut Vec<(PathBuf, Vec<String>)>) {
    let mut files = Vec::new();
    for entry in fs::read_dir(dir).expect("a readable folder") {
        let path = entry.expect("a folder entry").path();
        if path.is_dir() {
            folders(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let name = path.file_stem().unwrap().to_string_lossy().to_string();
            if name != "mod" {
                files.push(name);
            }
        }
    }
    files.sort();
    out.push((dir.to_path_buf(), files));
}

/// The files of one folder that each file names through `super::` (its sibling imports).
fn sibling_uses(dir: &Path, files: &[String]) -> BTreeMap<String, BTreeSet<String>> {
    let mut uses = BTreeMap::new();
    for f in files {
        let mut named = BTreeSet::new();
        for line in code_lines(&dir.join(format!("{f}.rs"))) {
            for (i, _) in line.match_indices("super::") {
                let rest = &line[i + "super::".len()..];
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                // `super::super::x` names the parent folder's modules, not a sibling.
                if name != *f && name != "super" && files.contains(&name) {
                    named.insert(name);
                }
            }
        }
        uses.insert(f.clone(), named);
    }
    uses
}

/// The files of `uses` that lie on a cycle (reachable from themselves).
fn on_cycles(uses: &BTreeMap<String, BTreeSet<String>>) -> BTreeSet<String> {
    let reaches = |from: &String| {
        let mut seen = BTreeSet::new();
        let mut stack: Vec<&String> = uses[from].iter().collect();
        while let Some(f) = stack.pop() {
            if seen.insert(f.clone()) {
                stack.extend(uses[f].iter());
            }
        }
        seen
    };
    uses.keys()
        .filter(|f| reaches(f).contains(*f))
        .cloned()
        .collect()
}

#[test]
fn no_folder_has_an_import_cycle() {
    let mut all = Vec::new();
    folders(Path::new("src"), &mut all);
    assert!(all.len() > 10, "the source folders are found");
    let mut cycles = Vec::new();
    for (dir, files) in &all {
        let on = on_cycles(&sibling_uses(dir, files));
        if !on.is_empty() {
            cycles.push(format!("{}: {on:?}", dir.display()));
        }
    }
    assert!(cycles.is_empty(), "import cycles: {cycles:#?}");
}

#[test]
fn the_cycle_finder_sees_a_cycle() {
    let uses: BTreeMap<String, BTreeSet<String>> = [
        ("a", vec!["b"]),
        ("b", vec!["c"]),
        ("c", vec!["a"]),
        ("d", vec!["a"]),
    ]
    .into_iter()
    .map(|(f, u)| (f.to_string(), u.into_iter().map(String::from).collect()))
    .collect();
    let on: Vec<String> = on_cycles(&uses).into_iter().collect();
    assert_eq!(on, ["a", "b", "c"]);
}

#[test]
fn only_the_ecs_folder_names_bevy_crates() {
    let mut all = Vec::new();
    folders(Path::new("src"), &mut all);
    let mut found = Vec::new();
    for (dir, files) in &all {
        if dir.starts_with("src/ecs") {
            continue;
        }
        for f in files.iter().map(String::as_str).chain(["mod"]) {
            let path = dir.join(format!("{f}.rs"));
            if !path.exists() {
                continue;
            }
            for line in code_lines(&path) {
                // `lib.rs` may name a cargo feature (`cfg(feature = "bevy_mesh")`).
                let uses_crate = line.contains("bevy_") && !line.contains("feature = \"bevy_");
                if uses_crate {
                    found.push(format!("{}: {line}", path.display()));
                }
            }
        }
    }
    assert!(found.is_empty(), "bevy outside src/ecs: {found:#?}");
}
