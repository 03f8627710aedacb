//! The product's documents describe the product as it is: none narrates
//! how or when it was built ("session 12", "sessions 3 and 4"), which is
//! git's and the closing notes' to keep.

use std::path::{Path, PathBuf};

/// The documents a user reads: the README, `docs/`, and each crate's and
/// the firmware's README.
fn documents() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut out = vec![root.join("README.md"), root.join("firmware/README.md")];
    for dir in ["docs", "crates"] {
        for entry in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = entry.unwrap().path();
            if p.extension().is_some_and(|e| e == "md") {
                out.push(p);
            } else if p.join("README.md").is_file() {
                out.push(p.join("README.md"));
            }
        }
    }
    out
}

/// Where `text` says "session" or "sessions" followed by a number.
fn session_mentions(text: &str) -> Vec<String> {
    let words: Vec<&str> = text.split_whitespace().collect();
    words
        .windows(2)
        .filter(|w| {
            let word = w[0]
                .trim_matches(|c: char| !c.is_alphanumeric())
                .to_lowercase();
            (word == "session" || word == "sessions")
                && w[1]
                    .trim_start_matches(|c: char| !c.is_alphanumeric())
                    .starts_with(|c: char| c.is_ascii_digit())
        })
        .map(|w| w.join(" "))
        .collect()
}

#[test]
fn no_document_narrates_development_sessions() {
    let docs = documents();
    assert!(docs.len() >= 9, "{docs:?}");
    for path in docs {
        let text = std::fs::read_to_string(&path).unwrap();
        let found = session_mentions(&text);
        assert!(found.is_empty(), "{}: {found:?}", path.display());
    }
}

#[test]
fn the_check_finds_what_it_looks_for() {
    assert_eq!(session_mentions("as in Session 12, the"), ["Session 12,"]);
    assert_eq!(session_mentions("(sessions 3 and 4)").len(), 1);
    assert!(session_mentions("each session starts; a session's tick").is_empty());
}
