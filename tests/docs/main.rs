//! The documentation as a book: README.md is a front page within 15 KB with the two commands,
//! docs/README.md indexes every chapter, each chapter opens with its title and a line of
//! purpose, and every relative link of README.md and docs/ resolves to a file.

use std::fs;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &Path) -> String {
    fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The Markdown files of the book: README.md and every docs/*.md.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![root().join("README.md")];
    pages.extend(chapters());
    pages
}

/// docs/*.md, the index included, sorted.
fn chapters() -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = fs::read_dir(root().join("docs"))
        .expect("docs/")
        .map(|e| e.expect("docs entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    out.sort();
    out
}

/// The targets of the inline links `[text](target)` outside fenced code blocks and code spans,
/// with their line numbers.
fn links(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut fenced = false;
    for (n, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // Drop code spans: a `](` inside backticks is no link.
        let plain: String = line
            .split('`')
            .enumerate()
            .filter(|(i, _)| i % 2 == 0)
            .map(|(_, s)| s)
            .collect::<Vec<_>>()
            .join(" ");
        let mut rest = plain.as_str();
        while let Some(i) = rest.find("](") {
            rest = &rest[i + 2..];
            let end = rest.find(')').unwrap_or(rest.len());
            let target = rest[..end].split_whitespace().next().unwrap_or("");
            out.push((n + 1, target.to_owned()));
            rest = &rest[end..];
        }
    }
    out
}

fn is_external(target: &str) -> bool {
    target.contains("://") || target.starts_with("mailto:")
}

#[test]
fn every_relative_link_resolves_to_a_file() {
    let mut broken = Vec::new();
    for page in pages() {
        let dir = page.parent().expect("a page has a folder");
        for (line, target) in links(&read(&page)) {
            if target.is_empty() || is_external(&target) || target.starts_with('#') {
                continue;
            }
            let file = target.split('#').next().unwrap_or("");
            if !dir.join(file).exists() {
                broken.push(format!("{}:{line}: {target}", page.display()));
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn the_index_lists_every_chapter() {
    let index = read(&root().join("docs/README.md"));
    let listed: Vec<String> = links(&index).into_iter().map(|(_, t)| t).collect();
    let missing: Vec<String> = chapters()
        .iter()
        .filter_map(|p| p.file_name()?.to_str().map(str::to_owned))
        .filter(|name| name != "README.md" && !listed.iter().any(|t| t == name))
        .collect();
    assert!(
        missing.is_empty(),
        "docs/README.md does not link these chapters: {missing:?}"
    );
}

#[test]
fn every_chapter_opens_with_a_title_and_a_purpose() {
    for page in chapters() {
        let text = read(&page);
        let mut lines = text.lines();
        let title = lines.next().unwrap_or("");
        assert!(title.starts_with("# "), "{}: no title", page.display());
        let first = lines.find(|l| !l.trim().is_empty()).unwrap_or("");
        assert!(
            !first.starts_with(['#', '|', '<', '-', '!']),
            "{}: the title is not followed by a line of purpose but {first:?}",
            page.display()
        );
    }
}

#[test]
fn the_front_page_is_short_and_gives_the_two_commands() {
    let readme = read(&root().join("README.md"));
    assert!(
        readme.len() <= 15_000,
        "README.md is {} bytes: the reference belongs in docs/",
        readme.len()
    );
    for command in ["cargo run --release -- demo", "scripts/test.sh"] {
        assert!(readme.contains(command), "README.md lacks `{command}`");
    }
    assert!(
        read(&root().join(".ci/run")).contains("scripts/test.sh"),
        ".ci/run no longer runs README's test command"
    );
}
