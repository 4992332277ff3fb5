//! The XML layer: MJCF text to a small element tree (tag, attributes, children,
//! file and line), with `<include>` expanded in place. Untrusted input: a DOCTYPE
//! or entity declaration is refused, no entity is expanded, and the only other
//! files read are the `<include>`d ones, relative to the model's directory
//! (MuJoCo's rule), at most [`MAX_INCLUDE_DEPTH`] deep and never in a cycle.

use super::MjcfError;
use quick_xml::events::{BytesStart, Event};
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Nested includes deeper than this are refused (a cycle is refused at once).
pub(super) const MAX_INCLUDE_DEPTH: usize = 16;

/// One element: its tag, attributes in file order, children, and where it was read.
#[derive(Clone, Debug)]
pub(crate) struct El {
    pub tag: String,
    pub attrs: Vec<(String, String)>,
    pub children: Vec<El>,
    /// The file it was read from (the model, or an included file).
    pub file: Rc<str>,
    /// 1-based line of its start tag.
    pub line: usize,
}

impl El {
    pub fn attr(&self, k: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(a, _)| a == k)
            .map(|(_, v)| v.as_str())
    }
    /// `<tag name="…">` or `<tag> (line N)`: how errors name the element.
    pub fn label(&self) -> String {
        match self.attr("name") {
            Some(n) => format!("<{} name=\"{n}\">", self.tag),
            None => format!("<{}> (line {})", self.tag, self.line),
        }
    }
    pub fn err(&self, msg: impl Into<String>) -> MjcfError {
        MjcfError::new(&self.file, Some(self.label()), msg)
    }
}

/// Reads `text` (named `file` in errors) into its root element, `<include>`s
/// expanded with files under `base_dir`.
/// `main` is the model file itself when there is one (an include of it is a cycle).
pub(crate) fn read(
    text: &str,
    file: &str,
    base_dir: &Path,
    main: Option<&Path>,
) -> Result<El, MjcfError> {
    let mut stack: Vec<PathBuf> = main
        .and_then(|p| std::fs::canonicalize(p).ok())
        .into_iter()
        .collect();
    let root = parse_one(text, file)?;
    if root.tag != "mujoco" {
        return Err(MjcfError::new(
            file,
            Some(format!("<{}>", root.tag)),
            "the root element is not <mujoco>",
        ));
    }
    expand(root, base_dir, &mut stack, 0)
}

/// Replaces every `<include file>` below `el` by the children of the included
/// file's `<mujoco>` root.
fn expand(
    mut el: El,
    base_dir: &Path,
    stack: &mut Vec<PathBuf>,
    depth: usize,
) -> Result<El, MjcfError> {
    let children = std::mem::take(&mut el.children);
    for c in children {
        if c.tag != "include" {
            el.children.push(expand(c, base_dir, stack, depth)?);
            continue;
        }
        let name = c
            .attr("file")
            .ok_or_else(|| c.err("missing attribute file"))?;
        if depth >= MAX_INCLUDE_DEPTH {
            return Err(c.err(format!(
                "file=\"{name}\": includes nested deeper than {MAX_INCLUDE_DEPTH}"
            )));
        }
        let path = base_dir.join(name);
        let canon = std::fs::canonicalize(&path).map_err(|e| {
            c.err(format!(
                "file=\"{name}\": cannot read {}: {e}",
                path.display()
            ))
        })?;
        if stack.contains(&canon) {
            return Err(c.err(format!("file=\"{name}\": cyclic include")));
        }
        let text = std::fs::read(&canon)
            .ok()
            .and_then(|b| String::from_utf8(b).ok())
            .ok_or_else(|| {
                c.err(format!(
                    "file=\"{name}\": cannot read {} as UTF-8 text",
                    path.display()
                ))
            })?;
        let inc = parse_one(&text, &path.display().to_string())?;
        if inc.tag != "mujoco" {
            return Err(c.err(format!(
                "file=\"{name}\": the included file's root is <{}>, not <mujoco>",
                inc.tag
            )));
        }
        stack.push(canon);
        let inc = expand(inc, base_dir, stack, depth + 1)?;
        stack.pop();
        el.children.extend(inc.children);
    }
    Ok(el)
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Parses one XML document into its root element.
fn parse_one(text: &str, file: &str) -> Result<El, MjcfError> {
    if text.trim().is_empty() {
        return Err(MjcfError::new(file, None, "empty file"));
    }
    if text.contains("<!ENTITY") || text.contains("<!DOCTYPE") {
        return Err(MjcfError::new(
            file,
            Some("<!DOCTYPE>".into()),
            "document type and entity declarations are not allowed",
        ));
    }
    let frc: Rc<str> = Rc::from(file);
    let mut reader = quick_xml::Reader::from_str(text);
    let mut stack: Vec<El> = Vec::new();
    let mut root: Option<El> = None;
    // line counting: newlines before the byte offset `pos`
    let (mut counted_to, mut line) = (0usize, 1usize);
    let mut line_at = |pos: usize| {
        let pos = pos.min(text.len());
        if pos > counted_to {
            line += text.as_bytes()[counted_to..pos]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            counted_to = pos;
        }
        line
    };
    loop {
        let start = reader.buffer_position() as usize;
        let ev = reader.read_event().map_err(|e| {
            MjcfError::new(
                file,
                stack.last().map(El::label),
                format!(
                    "not well-formed XML at byte {}: {}",
                    reader.error_position(),
                    one_line(&e.to_string())
                ),
            )
        })?;
        // the start tag begins after any whitespace the event skipped
        let skip = text.as_bytes()[start.min(text.len())..]
            .iter()
            .take_while(|b| b.is_ascii_whitespace())
            .count();
        match ev {
            Event::Start(e) | Event::Empty(e) if root.is_some() => {
                return Err(MjcfError::new(
                    file,
                    Some(format!("<{}>", String::from_utf8_lossy(e.name().as_ref()))),
                    "content after the root element",
                ));
            }
            Event::Start(e) => {
                let el = element(&e, &frc, line_at(start + skip))?;
                stack.push(el);
            }
            Event::Empty(e) => {
                let el = element(&e, &frc, line_at(start + skip))?;
                match stack.last_mut() {
                    Some(p) => p.children.push(el),
                    None => root = Some(el),
                }
            }
            Event::End(_) => {
                if let Some(el) = stack.pop() {
                    match stack.last_mut() {
                        Some(p) => p.children.push(el),
                        None => root = Some(el),
                    }
                }
            }
            Event::GeneralRef(r) => {
                let name = String::from_utf8_lossy(&r).into_owned();
                let predefined = matches!(name.as_str(), "lt" | "gt" | "amp" | "apos" | "quot");
                let valid_char = r.is_char_ref() && matches!(r.resolve_char_ref(), Ok(Some(_)));
                if !predefined && !valid_char {
                    return Err(MjcfError::new(
                        file,
                        stack.last().map(El::label),
                        format!("undeclared or invalid entity reference &{name};"),
                    ));
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    if let Some(open) = stack.last() {
        return Err(open.err("truncated XML: unclosed elements at end of file"));
    }
    root.ok_or_else(|| MjcfError::new(file, None, "no root element"))
}

fn element(e: &BytesStart, file: &Rc<str>, line: usize) -> Result<El, MjcfError> {
    let tag = String::from_utf8_lossy(e.name().as_ref()).into_owned();
    let mut attrs: Vec<(String, String)> = Vec::new();
    for a in e.attributes() {
        let a = a.map_err(|err| {
            MjcfError::new(
                file,
                Some(format!("<{tag}> (line {line})")),
                format!("malformed attribute: {}", one_line(&err.to_string())),
            )
        })?;
        let v = a.unescape_value().map_err(|err| {
            MjcfError::new(
                file,
                Some(format!("<{tag}> (line {line})")),
                format!("attribute: {}", one_line(&err.to_string())),
            )
        })?;
        attrs.push((
            String::from_utf8_lossy(a.key.as_ref()).into_owned(),
            v.into_owned(),
        ));
    }
    Ok(El {
        tag,
        attrs,
        children: Vec::new(),
        file: file.clone(),
        line,
    })
}

/// Whether `text` is MJCF: its root element is `<mujoco>` (comments, the XML
/// declaration and whitespace before it are skipped; nothing is parsed further).
pub fn is_mjcf_text(text: &str) -> bool {
    let mut reader = quick_xml::Reader::from_str(text);
    loop {
        match reader.read_event() {
            Ok(Event::Start(e)) | Ok(Event::Empty(e)) => return e.name().as_ref() == b"mujoco",
            Ok(Event::Eof) | Err(_) => return false,
            _ => {}
        }
    }
}
