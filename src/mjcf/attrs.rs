//! An element's attributes after its `<default>` class (MuJoCo's defaults: a
//! class holds, per element kind, the attributes its elements start from; a
//! nested class starts from its parent's), read as checked numbers.

use super::xml::El;
use super::MjcfError;
use std::collections::HashMap;

/// Per class, per element kind, its attributes (parents' folded in).
#[derive(Clone, Debug, Default)]
pub(crate) struct Defaults {
    pub classes: HashMap<String, HashMap<String, Vec<(String, String)>>>,
}

impl Defaults {
    /// Reads every top-level `<default>` (the unnamed one is class `main`).
    pub fn read(sections: &[&El]) -> Result<Self, MjcfError> {
        let mut d = Defaults::default();
        d.classes.insert("main".into(), HashMap::new());
        for s in sections {
            let name = s.attr("class").unwrap_or("main").to_string();
            d.class(s, &name, None)?;
        }
        Ok(d)
    }

    fn class(&mut self, el: &El, name: &str, parent: Option<&str>) -> Result<(), MjcfError> {
        let mut map = match parent {
            Some(p) => self.classes.get(p).cloned().unwrap_or_default(),
            None => self.classes.get(name).cloned().unwrap_or_default(),
        };
        for c in &el.children {
            if c.tag == "default" {
                continue;
            }
            let e = map.entry(c.tag.clone()).or_default();
            for (k, v) in &c.attrs {
                if k == "class" || k == "name" {
                    continue;
                }
                match e.iter_mut().find(|(a, _)| a == k) {
                    Some(slot) => slot.1 = v.clone(),
                    None => e.push((k.clone(), v.clone())),
                }
            }
        }
        self.classes.insert(name.to_string(), map);
        for c in el.children.iter().filter(|c| c.tag == "default") {
            let child = c
                .attr("class")
                .ok_or_else(|| c.err("a nested <default> needs a class"))?;
            if self.classes.contains_key(child) && child != "main" {
                return Err(c.err(format!("class=\"{child}\": duplicate default class")));
            }
            self.class(c, child, Some(name))?;
        }
        Ok(())
    }

    /// `el`'s attributes over its class's defaults for its kind: the class is its
    /// `class` attribute, else `childclass` (the enclosing body's or frame's).
    pub fn resolve<'a>(&'a self, el: &'a El, childclass: &str) -> Result<Attrs<'a>, MjcfError> {
        let class = el.attr("class").unwrap_or(childclass);
        let defaults = self
            .classes
            .get(class)
            .ok_or_else(|| el.err(format!("class=\"{class}\": unknown default class")))?;
        let base = if el.tag == "freejoint" {
            None
        } else {
            defaults.get(&el.tag)
        };
        Ok(Attrs { el, base })
    }

    /// As [`Defaults::resolve`], with the defaults of element kind `kind` (a
    /// `<fixed>` tendon takes `<default><tendon>`); `kind` empty: no defaults
    /// (a tendon's `<joint>` entries).
    pub fn resolve_as<'a>(
        &'a self,
        el: &'a El,
        childclass: &str,
        kind: &str,
    ) -> Result<Attrs<'a>, MjcfError> {
        let class = el.attr("class").unwrap_or(childclass);
        let defaults = self
            .classes
            .get(class)
            .ok_or_else(|| el.err(format!("class=\"{class}\": unknown default class")))?;
        let base = if kind.is_empty() {
            None
        } else {
            defaults.get(kind)
        };
        Ok(Attrs { el, base })
    }
}

/// An element's attributes with its class's defaults behind them.
pub(crate) struct Attrs<'a> {
    pub el: &'a El,
    base: Option<&'a Vec<(String, String)>>,
}

impl<'a> Attrs<'a> {
    /// The element's own value, else its class's.
    pub fn get(&self, k: &str) -> Option<&'a str> {
        self.el.attr(k).or_else(|| {
            self.base
                .and_then(|b| b.iter().find(|(a, _)| a == k).map(|(_, v)| v.as_str()))
        })
    }
    fn class_value(&self, k: &str) -> Option<&'a str> {
        self.base
            .and_then(|b| b.iter().find(|(a, _)| a == k).map(|(_, v)| v.as_str()))
    }
    pub fn err(&self, k: &str, msg: impl std::fmt::Display) -> MjcfError {
        let v = self.get(k).unwrap_or("");
        self.el.err(format!("{k}=\"{v}\": {msg}"))
    }
    fn parse(&self, k: &str, s: &str) -> Result<Vec<f64>, MjcfError> {
        s.split_whitespace()
            .map(|p| {
                let x: f64 = p.parse().map_err(|_| self.err(k, "is not numeric"))?;
                if x.is_finite() {
                    Ok(x)
                } else {
                    Err(self.err(k, "is not a finite number"))
                }
            })
            .collect()
    }
    /// All the numbers of attribute `k`, if present.
    pub fn numbers(&self, k: &str) -> Result<Option<Vec<f64>>, MjcfError> {
        match self.get(k) {
            None => Ok(None),
            Some(s) => self.parse(k, s).map(Some),
        }
    }
    /// Exactly `N` numbers.
    pub fn arr<const N: usize>(&self, k: &str) -> Result<Option<[f64; N]>, MjcfError> {
        match self.numbers(k)? {
            None => Ok(None),
            Some(v) => <[f64; N]>::try_from(v)
                .map(Some)
                .map_err(|_| self.err(k, format!("needs {N} numbers"))),
        }
    }
    /// One number.
    pub fn num(&self, k: &str) -> Result<Option<f64>, MjcfError> {
        Ok(self.arr::<1>(k)?.map(|a| a[0]))
    }
    /// One number, at least 0.
    pub fn nonneg(&self, k: &str, default: f64) -> Result<f64, MjcfError> {
        let x = self.num(k)?.unwrap_or(default);
        if x < 0.0 {
            return Err(self.err(k, "must not be negative"));
        }
        Ok(x)
    }
    /// Up to `N` numbers over `init` (MuJoCo reads a short list into the first
    /// entries, the class's value or `init` keeping the rest).
    pub fn partial<const N: usize>(&self, k: &str, init: [f64; N]) -> Result<[f64; N], MjcfError> {
        let mut out = init;
        for s in [self.class_value(k), self.el.attr(k)].into_iter().flatten() {
            let v = self.parse(k, s)?;
            if v.len() > N {
                return Err(self.err(k, format!("has more than {N} numbers")));
            }
            for (o, x) in out.iter_mut().zip(v) {
                *o = x;
            }
        }
        Ok(out)
    }
    /// `true`/`false` (MuJoCo's booleans).
    pub fn flag(&self, k: &str) -> Result<Option<bool>, MjcfError> {
        match self.get(k) {
            None => Ok(None),
            Some("true") => Ok(Some(true)),
            Some("false") => Ok(Some(false)),
            Some(_) => Err(self.err(k, "must be true or false")),
        }
    }
    /// An integer.
    pub fn int(&self, k: &str) -> Result<Option<i64>, MjcfError> {
        match self.get(k) {
            None => Ok(None),
            Some(s) => s
                .trim()
                .parse()
                .map(Some)
                .map_err(|_| self.err(k, "is not an integer")),
        }
    }
    /// Refuses attributes outside `known` (names the first).
    pub fn check_known(&self, known: &[&str]) -> Result<(), MjcfError> {
        for (k, _) in &self.el.attrs {
            if k != "class" && !known.contains(&k.as_str()) {
                return Err(self.el.err(format!("unknown attribute {k}")));
            }
        }
        Ok(())
    }
}
