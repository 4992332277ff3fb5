//! The tests of `src/mesh/cache.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use std::cell::Cell;
use urdyn::testing::mesh::cached_text;

#[test]
fn a_changed_file_is_made_again_and_an_unchanged_one_is_not() {
    let dir = std::env::temp_dir().join(format!("urdyn-cache-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let path = dir.join("m.txt");
    std::fs::write(&path, "abc").expect("written");
    let calls = Cell::new(0);
    let read = || -> Result<String, String> {
        calls.set(calls.get() + 1);
        std::fs::read_to_string(&path).map_err(|e| e.to_string())
    };
    let first = cached_text("test-text", &path, [1.0; 3], &read).expect("read");
    let again = cached_text("test-text", &path, [1.0; 3], &read).expect("read");
    assert_eq!((first.as_str(), again.as_str()), ("abc", "abc"));
    assert_eq!(calls.get(), 1, "the second call reads nothing");
    // another scale, another entry
    cached_text("test-text", &path, [2.0, 1.0, 1.0], &read).expect("read");
    assert_eq!(calls.get(), 2);
    // another length: made again
    std::fs::write(&path, "abcd").expect("written");
    let changed = cached_text("test-text", &path, [1.0; 3], &read).expect("read");
    assert_eq!((*changed).as_str(), "abcd");
    assert_eq!(calls.get(), 3);
    // a failure is not kept
    let missing = dir.join("none.txt");
    let fail = || -> Result<String, String> { Err("no".into()) };
    assert!(cached_text("test-text", &missing, [1.0; 3], &fail).is_err());
    std::fs::remove_dir_all(&dir).ok();
}
