//! The workspace's layering, checked (issue #16): a crate's dependencies
//! show what it may touch, and the pure core touches no runtime, network,
//! GPU, database, file or thread API.
//!
//! - `cargo tree -p grade3d-core` (normal dependencies, every depth) lists
//!   none of tokio, axum, hyper, wgpu, redb; `grade3d-io` none of those
//!   either; `grade3d-render` no tokio, axum, hyper or redb.
//! - The core's sources (tests included) name no `std::fs`, `std::thread`,
//!   `std::process`, `std::net` or `tokio`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

/// Every package in `package`'s normal dependency tree, by name.
fn dependency_names(package: &str) -> Vec<String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args(["tree", "--offline", "-p", package, "-e", "normal", "--prefix", "none", "--format", "{p}"])
        .current_dir(root())
        .output()
        .expect("cargo runs");
    assert!(out.status.success(), "cargo tree -p {package}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_owned)
        .collect()
}

#[test]
fn each_crate_depends_only_on_what_its_layer_may_touch() {
    // the reading itself: the layers above do depend on what the core may not
    assert!(dependency_names("grade3d-render").iter().any(|n| n == "wgpu"));
    let service = dependency_names("grade3d-service");
    assert!(["tokio", "axum", "redb", "grade3d-core"].iter().all(|d| service.iter().any(|n| n == d)), "{service:?}");
    for (package, forbidden) in [
        ("grade3d-core", &["tokio", "axum", "hyper", "wgpu", "redb", "tower", "tower-http"][..]),
        ("grade3d-io", &["tokio", "axum", "hyper", "wgpu", "redb", "tower", "tower-http"][..]),
        ("grade3d-render", &["tokio", "axum", "hyper", "redb", "tower", "tower-http"][..]),
    ] {
        let names = dependency_names(package);
        assert!(names.iter().any(|n| n == "glam"), "{package}: the tree is read ({names:?})");
        for f in forbidden {
            assert!(!names.iter().any(|n| n == f), "{package} depends on {f}");
        }
    }
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn the_core_names_no_file_thread_process_network_or_async_api() {
    let mut files = Vec::new();
    rust_files(&root().join("crates/grade3d-core/src"), &mut files);
    assert!(files.len() > 40, "the core's sources: {}", files.len());
    let mut found = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for (i, line) in text.lines().enumerate() {
            for api in ["std::fs", "std::thread", "std::process", "std::net", "tokio"] {
                if line.contains(api) {
                    found.push(format!("{}:{}: {}", f.display(), i + 1, line.trim()));
                }
            }
        }
    }
    assert!(found.is_empty(), "the core names APIs it must not touch:\n{}", found.join("\n"));
}
