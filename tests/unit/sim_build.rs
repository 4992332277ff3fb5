//! The tests of `src/sim/build.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use urdyn::sim::SimOptions;

fn spec(json: &str) -> urdyn::scene::SceneSpec {
    serde_json::from_str(json).expect("a valid scene document")
}

/// `with_islands`: the caller's sleep/threads over the file's over the
/// options'; the file's velocity, time and never-sleeping models (scene.md
/// §"Large scenes"), each value read off the document by hand.
#[test]
fn the_caller_beats_the_file_which_beats_the_options() {
    let s = spec(
        r#"{"models": [{"name": "a", "urdf": "a.urdf", "sleep": false},
                       {"name": "b", "urdf": "b.urdf"}],
            "sleep": false, "sleep_velocity": 0.002, "sleep_time": 0.25, "threads": 3}"#,
    );
    let o = SimOptions::default().with_islands(Some(&s), None, None);
    assert!(!o.sleep);
    assert_eq!(
        (o.sleep_velocity, o.sleep_time, o.threads),
        (0.002, 0.25, 3)
    );
    assert_eq!(o.never_sleep, vec!["a".to_string()]);
    let o = SimOptions::default().with_islands(Some(&s), Some(true), Some(2));
    assert!(o.sleep);
    assert_eq!(o.threads, 2);
    // a file without the keys: the options' values (here not the defaults)
    let bare = spec(r#"{"models": [{"name": "a", "urdf": "a.urdf"}]}"#);
    let base = SimOptions {
        sleep: false,
        sleep_velocity: 0.5,
        sleep_time: 7.0,
        threads: 4,
        ..SimOptions::default()
    };
    let o = base.clone().with_islands(Some(&bare), None, None);
    assert!(!o.sleep);
    assert_eq!((o.sleep_velocity, o.sleep_time, o.threads), (0.5, 7.0, 4));
    assert!(o.never_sleep.is_empty());
    // a model alone: only the caller's over the options'
    let o = base.with_islands(None, Some(true), None);
    assert!(o.sleep);
    assert_eq!((o.sleep_velocity, o.sleep_time, o.threads), (0.5, 7.0, 4));
}
