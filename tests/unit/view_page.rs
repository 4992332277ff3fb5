//! The tests of `src/cli/view/page.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use urdyn::testing::view::base64;

#[test]
fn base64_matches_the_rfc_vectors() {
    // RFC 4648 §10.
    for (raw, enc) in [
        ("", ""),
        ("f", "Zg=="),
        ("fo", "Zm8="),
        ("foo", "Zm9v"),
        ("foob", "Zm9vYg=="),
        ("fooba", "Zm9vYmE="),
        ("foobar", "Zm9vYmFy"),
    ] {
        assert_eq!(base64(raw.as_bytes()), enc);
    }
    assert_eq!(base64(&[0xfb, 0xff]), "+/8=");
}
