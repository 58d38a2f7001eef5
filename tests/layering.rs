//! The architecture as a test: which module may use which (see ARCHITECTURE.md).
//!
//! Reads the sources as text. Test code (files named `*tests*.rs` and everything after a
//! `#[cfg(test)]` module declaration) is left out: tests may build whole worlds.

use std::path::{Path, PathBuf};

fn rs_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rs_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The non-test code of every source file under `src/FOLDER`, with its path.
fn code_of(folder: &str) -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rs_files(&root.join(folder), &mut files);
    files
        .into_iter()
        .filter(|p| !p.file_name().unwrap().to_string_lossy().contains("tests"))
        .map(|p| {
            let text = std::fs::read_to_string(&p).unwrap();
            let lines: Vec<&str> = text.lines().collect();
            let end = lines
                .windows(2)
                .position(|w| w[0].trim() == "#[cfg(test)]" && w[1].trim_start().starts_with("mod "))
                .unwrap_or(lines.len());
            let code = lines[..end]
                .iter()
                .filter(|l| !l.trim_start().starts_with("//"))
                .copied()
                .collect::<Vec<_>>()
                .join("\n");
            (p.strip_prefix(&root).unwrap().display().to_string(), code)
        })
        .collect()
}

/// The crate modules named by `crate::NAME` paths in `code`.
fn crate_modules(code: &str) -> Vec<String> {
    code.match_indices("crate::")
        .map(|(i, _)| {
            code[i + 7..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect::<String>()
        })
        .collect()
}

#[test]
fn kernels_never_see_the_world() {
    let mut bad = Vec::new();
    for folder in [
        "data",
        "model",
        "integrate",
        "constraints",
        "obstacles",
        "self_collision",
        "strands",
        "reference",
    ] {
        for (path, code) in code_of(folder) {
            if code.contains("crate::world") || code.contains("crate::World") || code.contains("impl World") {
                bad.push(path);
            }
        }
    }
    assert!(bad.is_empty(), "kernel modules that use the World: {bad:?}");
}

#[test]
fn the_reference_reads_only_data_and_model() {
    let mut bad = Vec::new();
    for (path, code) in code_of("reference") {
        for m in crate_modules(&code) {
            if !["data", "model", "error"].contains(&m.as_str()) {
                bad.push(format!("{path}: crate::{m}"));
            }
        }
    }
    assert!(bad.is_empty(), "the f64 reference must stay an independent reading: {bad:?}");
}

#[test]
fn data_and_model_depend_on_nothing_above_them() {
    let mut bad = Vec::new();
    for (folder, allowed) in [("data", &["data", "error"][..]), ("model", &["data", "model", "error"][..])] {
        for (path, code) in code_of(folder) {
            for m in crate_modules(&code) {
                if !allowed.contains(&m.as_str()) {
                    bad.push(format!("{path}: crate::{m}"));
                }
            }
        }
    }
    assert!(bad.is_empty(), "{bad:?}");
}

#[test]
fn module_tree_is_the_folder_tree() {
    let mut bad = Vec::new();
    for (path, code) in code_of("") {
        for (i, _) in code.match_indices("#[path") {
            let target: String = code[i..]
                .chars()
                .skip_while(|&c| c != '"')
                .skip(1)
                .take_while(|&c| c != '"')
                .collect();
            if !target.ends_with("_tests.rs") {
                bad.push(format!("{path}: {target}"));
            }
        }
    }
    assert!(bad.is_empty(), "#[path] outside *_tests.rs files: {bad:?}");
}
