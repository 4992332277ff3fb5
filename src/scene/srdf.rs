//! A small SRDF reader: the `<disable_collisions link1 link2>` pairs and the
//! `<group_state name>` poses (`<joint name value>`), everything else ignored.
//! Untrusted XML as the URDF's: no entity is expanded, no external file read.

use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;

/// What a scene reads of an SRDF.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Srdf {
    /// `<disable_collisions>` link pairs, in file order.
    pub disabled: Vec<(String, String)>,
    /// `<group_state>` poses in file order: the name and its joint values (a
    /// joint's `value` attribute as numbers; a 1-DoF joint has one).
    pub poses: Vec<(String, Vec<(String, Vec<f64>)>)>,
}

impl Srdf {
    /// The joint values of the named `<group_state>` (the first of that name).
    pub fn pose(&self, name: &str) -> Option<&[(String, Vec<f64>)]> {
        self.poses
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, j)| j.as_slice())
    }
}

fn attr(e: &BytesStart, key: &[u8]) -> Result<Option<String>, String> {
    for a in e.attributes() {
        let a = a.map_err(|err| format!("malformed attribute: {err}"))?;
        if a.key.as_ref() == key {
            let v = a
                .unescape_value()
                .map_err(|err| format!("malformed attribute value: {err}"))?;
            return Ok(Some(v.into_owned()));
        }
    }
    Ok(None)
}

fn need(e: &BytesStart, key: &[u8], tag: &str) -> Result<String, String> {
    attr(e, key)?.ok_or_else(|| {
        format!(
            "<{tag}> without a {} attribute",
            String::from_utf8_lossy(key)
        )
    })
}

/// Parses SRDF text; `Err` is a one-line message naming the element.
pub fn parse_srdf(text: &str) -> Result<Srdf, String> {
    if text.contains("<!ENTITY") {
        return Err("<!DOCTYPE>: entity declarations are not allowed".into());
    }
    if text.contains("<!DOCTYPE") {
        return Err("<!DOCTYPE>: document type declarations are not allowed".into());
    }
    let mut reader = Reader::from_str(text);
    let mut out = Srdf::default();
    // The group_state being read, if any.
    let mut state: Option<(String, Vec<(String, Vec<f64>)>)> = None;
    let mut saw_robot = false;
    loop {
        let ev = reader
            .read_event()
            .map_err(|e| format!("not well-formed XML: {e}"))?;
        let (e, empty) = match ev {
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(e) => {
                if e.name().as_ref() == b"group_state" {
                    if let Some(s) = state.take() {
                        out.poses.push(s);
                    }
                }
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        match e.name().as_ref() {
            b"robot" => saw_robot = true,
            b"disable_collisions" => {
                let a = need(&e, b"link1", "disable_collisions")?;
                let b = need(&e, b"link2", "disable_collisions")?;
                out.disabled.push((a, b));
            }
            b"group_state" => {
                let name = need(&e, b"name", "group_state")?;
                if empty {
                    out.poses.push((name, Vec::new()));
                } else {
                    state = Some((name, Vec::new()));
                }
            }
            b"joint" => {
                if let Some((sname, joints)) = state.as_mut() {
                    let name = need(&e, b"name", "joint")?;
                    let value = need(&e, b"value", "joint")?;
                    let vals: Result<Vec<f64>, _> =
                        value.split_whitespace().map(str::parse::<f64>).collect();
                    let vals = vals
                        .ok()
                        .filter(|v| !v.is_empty() && v.iter().all(|x| x.is_finite()))
                        .ok_or_else(|| {
                            format!(
                                "<group_state name=\"{sname}\"> <joint name=\"{name}\">: value \"{value}\" is not a list of finite numbers"
                            )
                        })?;
                    joints.push((name, vals));
                }
            }
            _ => {}
        }
    }
    if !saw_robot {
        return Err("no <robot> element".into());
    }
    Ok(out)
}
