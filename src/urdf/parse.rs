//! Parsing: an entity guard, a checking scan that names the offending element of
//! any malformed input, then urdf-rs's data model (`types.rs`, adapted from urdf-rs
//! 0.10) built directly from the XML with quick-xml (urdf-rs's own reader, through
//! xml-rs and serde, reads about 3 MB/s, its errors do not name the element, and its
//! dependencies were a fifth of the first build; its types and its URDF 1.0–1.2
//! semantics are kept).

use super::UrdfError;

#[path = "build.rs"]
mod build;
#[path = "rules.rs"]
mod rules;

use rules::{
    child_rules, known_attrs, known_children, numeric_arity, required_attrs, robot_version,
    JOINT_TYPES, MAX_DEPTH, SHAPES, SKIPPED_IN_LINK, SKIPPED_TOP_LEVEL,
};

/// The urdf-rs robot (links and joints; visuals and materials, which no dynamics
/// reads, are checked by the scan but not built) plus what the scan found.
pub(crate) struct Parsed {
    /// The robot as urdf-rs reads it.
    pub robot: super::types::Robot,
    /// Elements skipped whole (`<gazebo>`, `<transmission>`, `<sensor>`, xacro
    /// leftovers), one line a kind, as the import report prints them.
    pub ignored_tags: Vec<String>,
    /// Unknown attributes and elements, malformed visuals and materials.
    pub warnings: Vec<String>,
}

pub(crate) fn parse(text: &str, file: &str) -> Result<Parsed, UrdfError> {
    if text.trim().is_empty() {
        return Err(UrdfError::new(file, None, "empty file"));
    }
    // Untrusted XML: no entity is ever expanded and no external file is read.
    if text.contains("<!ENTITY") {
        return Err(UrdfError::new(
            file,
            Some("<!DOCTYPE>".into()),
            "entity declarations are not allowed",
        ));
    }
    if text.contains("<!DOCTYPE") {
        return Err(UrdfError::new(
            file,
            Some("<!DOCTYPE>".into()),
            "document type declarations are not allowed",
        ));
    }
    let mut scan = scan(text, file)?;
    let robot = build::build(text, file)?;
    Ok(Parsed {
        robot,
        ignored_tags: std::mem::take(&mut scan.ignored),
        warnings: scan.into_warnings(),
    })
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// How the scan treats an element and its subtree.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// Read by the dynamics (links, joints, collisions): a problem is an error.
    Strict,
    /// Known to the URDF specification but read by no dynamics (`<visual>`,
    /// `<material>`): a problem is a warning.
    Lenient,
    /// Not looked into (`<gazebo>`, `<transmission>`, unknown elements).
    Skip,
}

/// An open element during the scan.
struct Open {
    tag: String,
    /// How a top-level element is named in errors (`joint "j1"`); deeper elements
    /// are named by their path below it (`joint "j1" <origin>`), built on error only.
    label: Option<String>,
    children: Vec<String>,
    mode: Mode,
}

/// The error name of the element below `stack` called `tag` (or of the innermost
/// open element).
fn path_label(stack: &[Open], tag: Option<&str>) -> String {
    let mut s = String::new();
    let start = stack.iter().rposition(|o| o.label.is_some()).unwrap_or(0);
    for (i, o) in stack.iter().enumerate().skip(start) {
        match (&o.label, i == start) {
            (Some(l), true) => s.push_str(l),
            _ => {
                if !s.is_empty() {
                    s.push(' ');
                }
                s.push_str(&format!("<{}>", o.tag));
            }
        }
    }
    if let Some(t) = tag {
        if !s.is_empty() {
            s.push(' ');
        }
        s.push_str(&format!("<{t}>"));
    }
    s
}

/// What the checking scan found that is not an error.
struct Scan<'a> {
    file: &'a str,
    version: (u32, u32),
    seen_root: bool,
    ignored: Vec<String>,
    warnings: Vec<String>,
    /// Grouped warnings (unknown names, malformed visuals), one entry per kind
    /// (key): the first place's message, its suffix and how many places.
    grouped: Vec<(String, String, &'static str, usize)>,
}

impl Scan<'_> {
    /// Records an unknown attribute or element: one warning for each distinct
    /// name on each kind of element, naming its first place and counting the rest
    /// (a robot's vendor extensions do not drown its other warnings).
    fn unknown(&mut self, key: String, message: impl FnOnce() -> String) {
        self.group(key, message, "ignored");
    }

    /// A warning of kind `key`: the first one is kept, the others counted.
    fn group(&mut self, key: String, message: impl FnOnce() -> String, suffix: &'static str) {
        match self.grouped.iter_mut().find(|e| e.0 == key) {
            Some(entry) => entry.3 += 1,
            None => self.grouped.push((key, message(), suffix, 1)),
        }
    }

    /// The warnings, grouped ones last.
    fn into_warnings(self) -> Vec<String> {
        let mut w = self.warnings;
        for (_, msg, suffix, n) in self.grouped {
            w.push(if n == 1 {
                format!("{msg} ({suffix})")
            } else {
                format!("{msg} ({suffix}; {} more like it)", n - 1)
            });
        }
        w
    }

    /// An error in a strict element; a warning (the load goes on) in a lenient one.
    fn problem(&mut self, mode: Mode, label: &str, msg: String) -> Result<(), UrdfError> {
        match mode {
            Mode::Strict => Err(UrdfError::new(self.file, Some(label.to_string()), msg)),
            _ => {
                // Grouped by the label without its names: one warning for the
                // same defect in every link's visual.
                let key: String = label
                    .split('"')
                    .step_by(2)
                    .chain([msg.as_str()])
                    .collect::<Vec<_>>()
                    .join("|");
                self.group(key, || format!("{label}: {msg}"), "not used by dynamics");
                Ok(())
            }
        }
    }

    fn fail(&self, label: &str, msg: String) -> UrdfError {
        UrdfError::new(self.file, Some(label.to_string()), msg)
    }

    fn ignore(&mut self, what: String) {
        if !self.ignored.contains(&what) {
            self.ignored.push(what);
        }
    }

    /// The mode of a new element `tag` below `stack`; warns about an element the
    /// URDF specification does not have there.
    fn mode_of(&mut self, tag: &str, stack: &[Open]) -> Mode {
        let Some(parent) = stack.last() else {
            return Mode::Strict;
        };
        if parent.mode == Mode::Skip {
            return Mode::Skip;
        }
        if tag.starts_with("xacro:") {
            self.ignore(format!("<{tag}> elements (xacro leftovers, not expanded)"));
            return Mode::Skip;
        }
        if stack.len() == 1 {
            return match tag {
                "link" | "joint" => Mode::Strict,
                "material" => Mode::Lenient,
                _ if SKIPPED_TOP_LEVEL.contains(&tag) => {
                    self.ignore(format!("<{tag}> elements (not used by dynamics)"));
                    Mode::Skip
                }
                _ => {
                    self.unknown(format!("<{tag}> in <robot>"), || {
                        format!("unknown element <{tag}> in <robot>")
                    });
                    Mode::Skip
                }
            };
        }
        if parent.tag == "link" && SKIPPED_IN_LINK.contains(&tag) {
            self.ignore(format!(
                "<link> <{tag}> elements (PyBullet extension, not used by dynamics)"
            ));
            return Mode::Skip;
        }
        if !known_children(&parent.tag).contains(&tag) {
            self.unknown(format!("<{tag}> in <{}>", parent.tag), || {
                format!("unknown element <{tag}> in {}", path_label(stack, None))
            });
            return Mode::Skip;
        }
        if tag == "visual" {
            Mode::Lenient
        } else {
            parent.mode
        }
    }

    /// Opens an element: checks its attributes, returns its entry.
    fn open(
        &mut self,
        e: &quick_xml::events::BytesStart,
        stack: &[Open],
    ) -> Result<Open, UrdfError> {
        use std::borrow::Cow;
        let tag = String::from_utf8_lossy(e.name().as_ref()).into_owned();
        let here = |stack: &[Open]| path_label(stack, Some(&tag));
        if stack.len() >= MAX_DEPTH {
            // URDF needs about six levels; a deeper document is not a robot (and
            // would make the element trees below recurse deeply).
            let top = path_label(&stack[..2.min(stack.len())], None);
            return Err(self.fail(
                &top,
                format!("elements nested deeper than {MAX_DEPTH} levels"),
            ));
        }
        let mut attrs: Vec<(Cow<str>, Cow<str>)> = Vec::new();
        for a in e.attributes() {
            let a =
                a.map_err(|err| self.fail(&here(stack), format!("malformed attribute: {err}")))?;
            let key = String::from_utf8_lossy(a.key.into_inner());
            let value = a.unescape_value().map_err(|err| {
                self.fail(
                    &here(stack),
                    format!("attribute {key}: {}", one_line(&err.to_string())),
                )
            })?;
            attrs.push((key, value));
        }
        let get = |k: &str| attrs.iter().find(|(a, _)| a == k).map(|(_, v)| v.as_ref());
        let parent = stack.last().map(|p| p.tag.as_str()).unwrap_or("");
        let label = match (stack.len(), tag.as_str()) {
            (0, _) => {
                if self.seen_root {
                    return Err(self.fail(&here(stack), "more than one root element".into()));
                }
                if tag != "robot" {
                    return Err(self.fail(&here(stack), "the root element must be <robot>".into()));
                }
                self.seen_root = true;
                self.version = robot_version(get("version"));
                Some("<robot>".to_string())
            }
            (1, "link" | "joint" | "material") => Some(match get("name") {
                Some(n) => format!("{tag} \"{n}\""),
                None => {
                    let k = stack
                        .last()
                        .map_or(0, |p| p.children.iter().filter(|c| **c == tag).count());
                    format!("{tag} #{}", k + 1)
                }
            }),
            _ => None,
        };
        let mode = self.mode_of(&tag, stack);
        let label_str = |stack: &[Open]| match &label {
            Some(l) => l.clone(),
            None => here(stack),
        };
        if mode != Mode::Skip {
            let known = known_attrs(&tag).unwrap_or(&[]);
            for (k, _) in &attrs {
                if !known.contains(&k.as_ref()) && !k.starts_with("xmlns") {
                    self.unknown(format!("\"{k}\" on <{tag}>"), || {
                        let on = match &label {
                            Some(l) => l.clone(),
                            None => format!("<{tag}> of {}", path_label(stack, None)),
                        };
                        format!("unknown attribute \"{k}\" on {on}")
                    });
                }
            }
            if !stack.is_empty() {
                for req in required_attrs(&tag, parent, self.version) {
                    if get(req).is_none() {
                        self.problem(mode, &label_str(stack), format!("missing attribute {req}"))?;
                    }
                }
            }
            if tag == "joint" && parent == "robot" {
                if let Some(t) = get("type") {
                    if !JOINT_TYPES.contains(&t) {
                        return Err(self.fail(
                            &label_str(stack),
                            format!(
                                "unknown joint type \"{t}\" (expected one of {})",
                                JOINT_TYPES.join(", ")
                            ),
                        ));
                    }
                }
            }
            for (k, v) in &attrs {
                if let Some(n) = numeric_arity(&tag, k) {
                    let parts: Vec<&str> = v.split_whitespace().collect();
                    let ok = parts.len() == n && parts.iter().all(|p| p.parse::<f64>().is_ok());
                    if !ok {
                        let what = if n == 1 {
                            "a number".to_string()
                        } else {
                            format!("{n} numbers")
                        };
                        self.problem(
                            mode,
                            &label_str(stack),
                            format!("{k}=\"{v}\" is not {what}"),
                        )?;
                    }
                }
            }
        }
        Ok(Open {
            tag,
            label,
            children: Vec::new(),
            mode,
        })
    }

    /// Closes an element: checks its children.
    fn close(&mut self, o: Open, stack: &mut [Open]) -> Result<(), UrdfError> {
        let parent = stack.last().map(|p| p.tag.as_str()).unwrap_or("");
        let o_label = |stack: &[Open]| match &o.label {
            Some(l) => l.clone(),
            None => path_label(stack, Some(&o.tag)),
        };
        if o.mode != Mode::Skip {
            let (required, once) = child_rules(&o.tag, parent);
            for r in required {
                if !o.children.iter().any(|c| c == r) {
                    self.problem(o.mode, &o_label(stack), format!("missing <{r}>"))?;
                }
            }
            for r in once {
                if o.children.iter().filter(|c| *c == r).count() > 1 {
                    self.problem(o.mode, &o_label(stack), format!("more than one <{r}>"))?;
                }
            }
            if o.tag == "geometry" {
                let shapes = o
                    .children
                    .iter()
                    .filter(|c| SHAPES.contains(&c.as_str()))
                    .count();
                if shapes != 1 {
                    self.problem(
                        o.mode,
                        &o_label(stack),
                        format!(
                            "needs exactly one shape ({}), found {shapes}",
                            SHAPES.join(", ")
                        ),
                    )?;
                }
            }
        }
        if let Some(p) = stack.last_mut() {
            p.children.push(o.tag);
        }
        Ok(())
    }
}

/// Checks that the document is well-formed XML with a `<robot>` root, that every
/// element the dynamics reads has its required attributes and children, that
/// numeric attributes hold the right count of numbers, and that no undeclared
/// entity is referenced — each error naming the element. What no dynamics reads
/// never stops a load: a malformed `<visual>` or `<material>` is a warning,
/// `<gazebo>`, `<transmission>`, `<sensor>` and xacro leftovers are skipped whole
/// (listed as ignored), and an attribute or element outside the URDF specification
/// is a warning naming it and where it stands.
fn scan<'a>(text: &str, file: &'a str) -> Result<Scan<'a>, UrdfError> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(text);
    let mut stack: Vec<Open> = Vec::new();
    let mut scan = Scan {
        file,
        version: (1, 0),
        seen_root: false,
        ignored: Vec::new(),
        warnings: Vec::new(),
        grouped: Vec::new(),
    };
    loop {
        let ev = reader.read_event().map_err(|e| {
            let at = if stack.is_empty() {
                String::new()
            } else {
                format!("{}: ", path_label(&stack, None))
            };
            UrdfError::new(
                file,
                None,
                format!(
                    "{at}not well-formed XML at byte {}: {}",
                    reader.error_position(),
                    one_line(&e.to_string())
                ),
            )
        })?;
        match ev {
            Event::Start(e) => {
                let o = scan.open(&e, &stack)?;
                stack.push(o);
            }
            Event::Empty(e) => {
                let o = scan.open(&e, &stack)?;
                scan.close(o, &mut stack)?;
            }
            Event::End(_) => {
                if let Some(o) = stack.pop() {
                    scan.close(o, &mut stack)?;
                }
            }
            Event::GeneralRef(r) => {
                let name = String::from_utf8_lossy(&r).into_owned();
                let predefined = matches!(name.as_str(), "lt" | "gt" | "amp" | "apos" | "quot");
                let valid_char = r.is_char_ref() && matches!(r.resolve_char_ref(), Ok(Some(_)));
                if !predefined && !valid_char {
                    let label = if stack.is_empty() {
                        "<robot>".to_string()
                    } else {
                        path_label(&stack, None)
                    };
                    return Err(scan.fail(
                        &label,
                        format!("undeclared or invalid entity reference &{name};"),
                    ));
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    if !stack.is_empty() {
        return Err(scan.fail(
            &path_label(&stack, None),
            "truncated XML: unclosed elements at end of file".into(),
        ));
    }
    if !scan.seen_root {
        return Err(UrdfError::new(file, None, "no <robot> element"));
    }
    Ok(scan)
}
