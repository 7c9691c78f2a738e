//! docs/ARCHITECTURE.md's table of the builder's stages, checked against the module tree: every
//! module of a stage is named in its row, and every module a row names exists. A module added,
//! renamed or removed without the page is a failing test, not a page that drifts.

use std::collections::BTreeSet;
use std::path::Path;

/// The rows of the stage table: (stage folder, modules named at the top level of its cell).
fn table_rows(page: &str) -> Vec<(String, BTreeSet<String>)> {
    let section = page.split("## Builder stages").nth(1).expect("a section \"Builder stages\"");
    let section = section.split("\n## ").next().unwrap_or(section);
    let mut rows = Vec::new();
    for line in section.lines().filter(|l| l.starts_with("| ") && l.contains('`')) {
        let cells: Vec<&str> = line.split(" | ").collect();
        let Some(stage) = backticked_at_top(cells[0]).into_iter().next() else { continue };
        if cells.len() < 2 {
            continue;
        }
        let modules = backticked_at_top(cells[1])
            .into_iter()
            .map(|m| m.trim_end_matches('/').trim_end_matches(".rs").to_string())
            .filter(|m| m != "mod")
            .collect();
        rows.push((stage, modules));
    }
    rows
}

/// The `names` in backticks outside any parentheses: a cell's own list, not what its
/// descriptions mention.
fn backticked_at_top(cell: &str) -> Vec<String> {
    let mut depth = 0i32;
    let mut inside = None;
    let mut found = Vec::new();
    for (i, c) in cell.char_indices() {
        match c {
            '`' => match inside.take() {
                Some(start) => {
                    if depth == 0 {
                        found.push(cell[start..i].to_string());
                    }
                }
                None => inside = Some(i + 1),
            },
            '(' if inside.is_none() => depth += 1,
            ')' if inside.is_none() => depth -= 1,
            _ => {}
        }
    }
    found
}

/// Where a row's modules live: the stages that are crates of their own, else the builder's
/// `src/<stage>/`.
fn folder_of(root: &Path, stage: &str) -> std::path::PathBuf {
    match stage {
        "distributed" => root.join("../petsc-backend/src"),
        "linalg" => root.join("../fe-linalg/src"),
        "input" => root.join("../fe-input/src"),
        stage => root.join("src").join(stage),
    }
}

/// The modules directly in a stage's folder: its files but mod.rs and lib.rs, and its folders.
fn modules_of(stage: &Path) -> BTreeSet<String> {
    std::fs::read_dir(stage)
        .unwrap_or_else(|e| panic!("{}: {e}", stage.display()))
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.is_dir() || p.extension().is_some_and(|e| e == "rs"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .filter(|m| m != "mod" && m != "lib")
        .collect()
}

#[test]
fn the_cell_reader_keeps_the_list_and_skips_the_descriptions() {
    let cell = "`mod.rs` (`build`), `mounted` and `free_floating` (the `Support` strategy), `fmu/` (`guid`)";
    assert_eq!(backticked_at_top(cell), ["mod.rs", "mounted", "free_floating", "fmu/"]);
}

#[test]
fn every_stage_module_is_in_the_architecture_page_and_every_named_module_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let page = std::fs::read_to_string(root.join("../docs/ARCHITECTURE.md")).unwrap();
    let rows = table_rows(&page);
    let stages: Vec<&str> = rows.iter().map(|(s, _)| s.as_str()).collect();
    // the check must see the table, not pass on an empty one
    for stage in ["distributed", "linalg", "input", "model", "reduce", "ffrf", "output", "pipeline", "job"] {
        assert!(stages.contains(&stage), "no row for {stage} in {stages:?}");
    }
    let mut wrong = Vec::new();
    for (stage, named) in &rows {
        let actual = modules_of(&folder_of(root, stage));
        for m in actual.difference(named) {
            wrong.push(format!("{stage}/{m} is not named in its row"));
        }
        for m in named.difference(&actual) {
            wrong.push(format!("{stage}/{m} is named but does not exist"));
        }
    }
    assert!(wrong.is_empty(), "docs/ARCHITECTURE.md's stage table and the sources differ:\n{}", wrong.join("\n"));
}
