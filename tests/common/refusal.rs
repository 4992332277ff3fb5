//! The contract of a refused command line, shared by the CLI's bad-input tests.

/// Asserts that `urdyn ARGS` (named `ctx` in messages) was refused as a person
/// must be answered: non-zero exit, nothing on stdout, no panic or internal
/// error, one line on stderr holding every `expect` substring; returns the line.
pub fn assert_refused(
    ctx: &str,
    code: Option<i32>,
    stdout: &str,
    stderr: &str,
    expect: &[&str],
) -> String {
    assert!(
        code.is_some_and(|c| c != 0),
        "{ctx}: exit status {code:?}, stderr {stderr:?}"
    );
    assert!(stdout.is_empty(), "{ctx}: wrote to stdout: {stdout:?}");
    assert!(!stderr.contains("panicked"), "{ctx}: panicked: {stderr}");
    assert!(
        !stderr.contains("internal error"),
        "{ctx}: internal error: {stderr}"
    );
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(
        lines.len(),
        1,
        "{ctx}: expected one line on stderr, got {stderr:?}"
    );
    for e in expect {
        assert!(
            lines[0].contains(e),
            "{ctx}: error {:?} does not contain {e:?}",
            lines[0]
        );
    }
    lines[0].to_string()
}
