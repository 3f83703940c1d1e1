//! pbrt-v4 parameter lists (`"float fov" [45]`) and the directives that carry them. Each read
//! checks the declared type and marks the parameter used; [`Directive::check_all_used`] then
//! refuses whatever the mapping did not understand, naming its line.

use super::super::Location;
use anyhow::{anyhow, bail, Result};
use glam::DVec3;
use std::cell::Cell;
use std::fmt;

/// A parameter's values as written: numbers, strings, or booleans.
#[derive(Clone, Debug)]
pub enum Values {
    Numbers(Vec<f64>),
    Strings(Vec<String>),
    Bools(Vec<bool>),
}

#[derive(Debug)]
pub struct Param {
    /// The declared type: float, integer, rgb, spectrum, texture, ...
    pub ty: String,
    pub name: String,
    pub values: Values,
    pub at: Location,
    used: Cell<bool>,
}

/// The declared types pbrt-v4 knows, and the kind of values each takes.
const NUMERIC_TYPES: [&str; 13] = [
    "integer",
    "float",
    "point2",
    "vector2",
    "point3",
    "vector3",
    "normal3",
    "normal",
    "point",
    "vector",
    "rgb",
    "blackbody",
    "color",
];

impl Param {
    /// Checks that the values fit the declared type (`at` is the parameter's line).
    pub fn new(ty: String, name: String, values: Values, at: Location) -> Result<Param> {
        let fits = match (ty.as_str(), &values) {
            ("integer", Values::Numbers(v)) => v.iter().all(|x| x.fract() == 0.0),
            (t, Values::Numbers(_)) => NUMERIC_TYPES.contains(&t) || t == "spectrum",
            ("string" | "texture" | "spectrum", Values::Strings(s)) => ty != "spectrum" || s.len() == 1,
            ("bool", Values::Bools(_)) => true,
            _ => false,
        };
        let known =
            NUMERIC_TYPES.contains(&ty.as_str()) || matches!(ty.as_str(), "spectrum" | "string" | "texture" | "bool");
        if !known {
            bail!("{at}: '{ty} {name}': unknown parameter type '{ty}'");
        }
        if !fits {
            bail!("{at}: '{ty} {name}': the values are not {}", expected(&ty));
        }
        if ty == "color" {
            // pbrt-v3's name for rgb, which pbrt-v4 still reads.
            return Ok(Param { ty: "rgb".into(), name, values, at, used: Cell::new(false) });
        }
        Ok(Param { ty, name, values, at, used: Cell::new(false) })
    }

    pub fn numbers(&self) -> &[f64] {
        match &self.values {
            Values::Numbers(v) => v,
            _ => &[],
        }
    }

    pub fn strings(&self) -> &[String] {
        match &self.values {
            Values::Strings(v) => v,
            _ => &[],
        }
    }

    fn count(&self) -> usize {
        match &self.values {
            Values::Numbers(v) => v.len(),
            Values::Strings(v) => v.len(),
            Values::Bools(v) => v.len(),
        }
    }

    /// `file:line: 'float fov': message`.
    pub fn error(&self, message: impl fmt::Display) -> anyhow::Error {
        anyhow!("{}: '{} {}': {message}", self.at, self.ty, self.name)
    }
}

fn expected(ty: &str) -> &'static str {
    match ty {
        "integer" => "integers",
        "bool" => "true or false",
        "string" | "texture" => "strings",
        "spectrum" => "wavelength-value pairs or one spectrum name",
        _ => "numbers",
    }
}

/// A directive with a type and parameters: `Shape "sphere" "float radius" 2`.
#[derive(Debug)]
pub struct Directive {
    /// Shape, Material, LightSource, ...
    pub directive: &'static str,
    /// The type in quotes after it: sphere, diffuse, point, ...
    pub kind: String,
    pub at: Location,
    pub params: Vec<Param>,
}

impl Directive {
    /// `Shape "sphere"`, for messages.
    pub fn describe(&self) -> String {
        format!("{} \"{}\"", self.directive, self.kind)
    }

    /// `file:line: Shape "sphere": message`.
    pub fn error(&self, message: impl fmt::Display) -> anyhow::Error {
        anyhow!("{}: {}: {message}", self.at, self.describe())
    }

    /// The parameter called `name`, marked used.
    pub fn param(&self, name: &str) -> Option<&Param> {
        let p = self.params.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    /// The parameter called `name` if it has one of `types`, else an error naming its line.
    fn typed(&self, name: &str, types: &[&str]) -> Result<Option<&Param>> {
        match self.param(name) {
            Some(p) if !types.contains(&p.ty.as_str()) => {
                Err(p.error(format!("{}: '{name}' is a {}, not a {}", self.describe(), types.join(" or "), p.ty)))
            }
            p => Ok(p),
        }
    }

    fn one<'a>(&self, p: &'a Param) -> Result<&'a Param> {
        match p.count() {
            1 => Ok(p),
            n => Err(p.error(format!("{}: needs one value, got {n}", self.describe()))),
        }
    }

    pub fn float(&self, name: &str) -> Result<Option<f64>> {
        self.typed(name, &["float"])?.map(|p| Ok(self.one(p)?.numbers()[0])).transpose()
    }

    pub fn float_or(&self, name: &str, default: f64) -> Result<f64> {
        Ok(self.float(name)?.unwrap_or(default))
    }

    pub fn floats(&self, name: &str) -> Result<Option<&[f64]>> {
        Ok(self.typed(name, &["float"])?.map(Param::numbers))
    }

    pub fn integer(&self, name: &str) -> Result<Option<i64>> {
        self.typed(name, &["integer"])?.map(|p| Ok(self.one(p)?.numbers()[0] as i64)).transpose()
    }

    pub fn integers(&self, name: &str) -> Result<Option<&[f64]>> {
        Ok(self.typed(name, &["integer"])?.map(Param::numbers))
    }

    pub fn boolean(&self, name: &str, default: bool) -> Result<bool> {
        match self.typed(name, &["bool"])? {
            None => Ok(default),
            Some(p) => match &self.one(p)?.values {
                Values::Bools(b) => Ok(b[0]),
                _ => unreachable!("bool parameters hold booleans (Param::new)"),
            },
        }
    }

    pub fn string(&self, name: &str) -> Result<Option<&str>> {
        self.typed(name, &["string"])?.map(|p| Ok(self.one(p)?.strings()[0].as_str())).transpose()
    }

    /// One point (point3 or point).
    pub fn point(&self, name: &str) -> Result<Option<DVec3>> {
        match self.typed(name, &["point3", "point"])? {
            None => Ok(None),
            Some(p) => match p.numbers() {
                [x, y, z] => Ok(Some(DVec3::new(*x, *y, *z))),
                v => Err(p.error(format!("{}: needs 3 numbers, got {}", self.describe(), v.len()))),
            },
        }
    }

    /// A list of 3-vectors of one of `types` (point3, normal, ...).
    pub fn triples(&self, name: &str, types: &[&str]) -> Result<Option<Vec<DVec3>>> {
        match self.typed(name, types)? {
            None => Ok(None),
            Some(p) => {
                let v = p.numbers();
                if v.len() % 3 != 0 {
                    return Err(p.error(format!(
                        "{}: needs a multiple of 3 numbers, got {}",
                        self.describe(),
                        v.len()
                    )));
                }
                Ok(Some(v.chunks_exact(3).map(|c| DVec3::new(c[0], c[1], c[2])).collect()))
            }
        }
    }

    /// Refuses the first parameter no mapping read.
    pub fn check_all_used(&self) -> Result<()> {
        match self.params.iter().find(|p| !p.used.get()) {
            Some(p) => Err(p.error(format!("{}: the parameter '{}' is not supported", self.describe(), p.name))),
            None => Ok(()),
        }
    }
}
