//! Mitsuba 3 XML as a tree of objects: `<default>` parameters and their `$name` substitution,
//! `<include>`, `<path>`, `id`/`<ref>`, nested objects and typed properties with their
//! `<transform>`s composed. What the objects mean is `mitsuba.rs`'s business; this module only
//! reads the document faithfully and remembers where each thing was written, so that every later
//! error can name the file and line.

use super::{shown, Location};
use anyhow::{anyhow, bail, Context as _, Result};
use glam::{DMat4, DVec3};
use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use crate::input_file::{InputFiles, InputKind};

/// An `<include>` chain deeper than this is a cycle (or a hostile file).
const MAX_INCLUDE_DEPTH: usize = 16;
/// Files read for one scene, the scene and its includes, counting a file as often as it is included.
const MAX_FILES: usize = 4096;
/// Bytes of XML read for one scene, over all its files: four scene files at their size cap.
const MAX_TOTAL_BYTES: u64 = 4 * InputKind::Scene.cap();
/// Objects nested in objects deeper than this (each level is a recursion of the reader and of the
/// mapping) make a hostile file, not a scene.
const MAX_NESTING: usize = 256;
/// Text made by `$name` substitution in one scene, over all its attributes: a scene file's cap.
const MAX_SUBSTITUTED_BYTES: usize = InputKind::Scene.cap() as usize;

/// A typed property value, as written.
#[derive(Clone, Debug)]
pub enum Value {
    Integer(i64),
    Float(f64),
    Boolean(bool),
    String(String),
    Rgb(DVec3),
    /// A constant spectrum (one number) or (wavelength in nm, value) pairs.
    Spectrum(Vec<(f64, f64)>),
    Point(DVec3),
    Vector(DVec3),
    Transform(DMat4),
}

#[derive(Debug)]
pub struct Property {
    pub name: String,
    pub value: Value,
    pub at: Location,
    /// Set when the mapping reads it; properties nobody read are unsupported.
    pub used: Cell<bool>,
}

/// A plugin instance: `<bsdf type="diffuse" id="white">` with its properties and nested objects.
#[derive(Debug)]
pub struct Object {
    /// The element: bsdf, shape, emitter, sensor, film, sampler, rfilter, integrator, texture.
    pub tag: String,
    /// Its `type` attribute.
    pub plugin: String,
    pub id: Option<String>,
    pub at: Location,
    pub properties: Vec<Property>,
    /// Nested objects and `<ref>`s, each with the `name` it was given there (if any).
    children: Vec<(Option<String>, Child)>,
    /// One flag a child, as for properties.
    children_used: Vec<Cell<bool>>,
    /// Every object with an id in the document, for `<ref>`s, which may name an object defined
    /// later (Mitsuba resolves them once the whole document is read).
    ids: Ids,
}

type Ids = Rc<RefCell<HashMap<String, Rc<Object>>>>;

#[derive(Debug)]
enum Child {
    Nested(Rc<Object>),
    Ref { id: String, at: Location },
}

impl Object {
    /// `<bsdf type="diffuse">`, for messages.
    pub fn describe(&self) -> String {
        match &self.id {
            Some(id) => format!("<{} type=\"{}\" id=\"{id}\">", self.tag, self.plugin),
            None => format!("<{} type=\"{}\">", self.tag, self.plugin),
        }
    }
}

/// The parsed scene: its top-level objects in document order.
pub struct Document {
    pub objects: Vec<Rc<Object>>,
}

/// Reads `path` and every file it includes. `defines` are `-D name=value`, overriding `<default>`.
pub fn read(
    files: &InputFiles,
    path: &Path,
    defines: &[(String, String)],
    resolver: &mut Resolver,
) -> Result<Document> {
    let mut reader = Reader {
        files,
        params: defines.iter().cloned().collect(),
        ids: Ids::default(),
        objects: vec![],
        depth: 0,
        files_read: 0,
        bytes_read: 0,
        substituted: Cell::new(0),
    };
    reader.read_file(path, resolver)?;
    Ok(Document { objects: reader.objects })
}

/// Where relative file names are looked for, in order: the main scene's folder, each `<path>`
/// folder, then the folder of the file that names it.
pub struct Resolver {
    pub folders: Vec<PathBuf>,
}

impl Resolver {
    pub fn new(scene: &Path) -> Resolver {
        Resolver { folders: vec![scene.parent().map(Path::to_path_buf).unwrap_or_default()] }
    }

    /// The first existing candidate, or the first candidate (so the error names a real place).
    pub fn resolve(&self, name: &str, from: &Path) -> PathBuf {
        let p = Path::new(name);
        if p.is_absolute() {
            return p.to_path_buf();
        }
        let from_folder = from.parent().map(Path::to_path_buf).unwrap_or_default();
        let candidates: Vec<PathBuf> =
            self.folders.iter().chain(std::iter::once(&from_folder)).map(|f| f.join(p)).collect();
        candidates.iter().find(|c| c.exists()).unwrap_or(&candidates[0]).clone()
    }
}

struct Reader<'a> {
    files: &'a InputFiles,
    /// `<default>` and `-D` parameters for `$name` substitution.
    params: HashMap<String, String>,
    ids: Ids,
    objects: Vec<Rc<Object>>,
    depth: usize,
    /// Files and bytes read so far, bounded by [`MAX_FILES`] and [`MAX_TOTAL_BYTES`].
    files_read: usize,
    bytes_read: u64,
    /// Bytes `$name` substitution has made so far, bounded by [`MAX_SUBSTITUTED_BYTES`].
    substituted: Cell<usize>,
}

/// One XML file being read: its name for messages and where its lines start.
struct Source {
    path: PathBuf,
    file: Rc<str>,
    /// The byte offset of each line's start, in order: a node's line is found by binary search (a
    /// scan from the start per node would make reading quadratic in the file's size).
    line_starts: Vec<usize>,
}

impl Source {
    fn new(path: &Path, name: &str, text: &str) -> Source {
        let line_starts = std::iter::once(0).chain(text.match_indices('\n').map(|(at, _)| at + 1)).collect();
        Source { path: path.to_path_buf(), file: Rc::from(name), line_starts }
    }

    fn at(&self, node: roxmltree::Node) -> Location {
        let line = self.line_starts.partition_point(|&start| start <= node.range().start) as u32;
        Location { file: self.file.clone(), line }
    }
}

/// Element names that are objects (plugin instances) rather than properties.
const OBJECT_TAGS: [&str; 12] = [
    "bsdf",
    "shape",
    "emitter",
    "sensor",
    "film",
    "sampler",
    "rfilter",
    "integrator",
    "texture",
    "medium",
    "phase",
    "volume",
];

impl Reader<'_> {
    fn read_file(&mut self, path: &Path, resolver: &mut Resolver) -> Result<()> {
        if self.depth > MAX_INCLUDE_DEPTH {
            bail!("{}: includes nest more than {MAX_INCLUDE_DEPTH} deep (an include cycle?)", path.display());
        }
        self.files_read += 1;
        if self.files_read > MAX_FILES {
            bail!("{}: the scene reads more than {MAX_FILES} files through <include>s", path.display());
        }
        let text = self.files.read_to_string(path, InputKind::Scene)?;
        self.bytes_read += text.len() as u64;
        if self.bytes_read > MAX_TOTAL_BYTES {
            bail!(
                "{}: the scene reads more than {} of XML through <include>s",
                path.display(),
                crate::input_file::describe_bytes(MAX_TOTAL_BYTES)
            );
        }
        let name = path.display().to_string();
        let doc = roxmltree::Document::parse(&text).map_err(|e| anyhow!("{name}: not well-formed XML: {e}"))?;
        let source = Source::new(path, &name, &text);
        let root = doc.root_element();
        if root.tag_name().name() != "scene" {
            bail!("{}: the root element is <{}>, not <scene>", source.at(root), root.tag_name().name());
        }
        self.check_version(&source, root)?;
        for node in root.children().filter(|n| n.is_element()) {
            self.top_level(&source, node, resolver)?;
        }
        Ok(())
    }

    /// Mitsuba 0.x scenes name their parameters differently; refuse them rather than misread them.
    fn check_version(&self, source: &Source, root: roxmltree::Node) -> Result<()> {
        let version = root.attribute("version").with_context(|| {
            format!("{}: <scene> has no version attribute (Mitsuba 3 scenes say version=\"3.0.0\")", source.at(root))
        })?;
        let major = version.split('.').next().and_then(|m| m.parse::<u32>().ok());
        if !matches!(major, Some(2 | 3)) {
            bail!("{}: scene version {version} is not supported (Mitsuba 2 and 3 scenes only)", source.at(root));
        }
        Ok(())
    }

    fn top_level(&mut self, source: &Source, node: roxmltree::Node, resolver: &mut Resolver) -> Result<()> {
        let at = source.at(node);
        match node.tag_name().name() {
            "default" => {
                let name = self.raw_attr(source, node, "name")?;
                let value = self.raw_attr(source, node, "value")?;
                // -D and earlier defaults win.
                self.params.entry(name.to_owned()).or_insert(value.to_owned());
            }
            "include" => {
                let file = resolver.resolve(&self.attr(source, node, "filename")?, &source.path);
                self.depth += 1;
                self.read_file(&file, resolver)
                    .with_context(|| format!("{at}: in the <include> of {}", file.display()))?;
                self.depth -= 1;
            }
            "path" => {
                let folder = resolver.resolve(&self.attr(source, node, "value")?, &source.path);
                resolver.folders.push(folder);
            }
            tag if OBJECT_TAGS.contains(&tag) => {
                let object = self.object(source, node, 0)?;
                self.objects.push(object);
            }
            tag => bail!("{at}: <{tag}> is not supported at the scene level"),
        }
        Ok(())
    }

    /// An object element, its id registered for later `<ref>`s; `nesting`: the objects around it.
    fn object(&mut self, source: &Source, node: roxmltree::Node, nesting: usize) -> Result<Rc<Object>> {
        let at = source.at(node);
        if nesting >= MAX_NESTING {
            bail!("{at}: objects nest more than {MAX_NESTING} deep");
        }
        let tag = node.tag_name().name().to_owned();
        let plugin = self.attr(source, node, "type")?;
        let id = node.attribute("id").map(|i| self.substitute(source, node, i)).transpose()?;
        let mut object = Object {
            tag,
            plugin,
            id: id.clone(),
            at: at.clone(),
            properties: vec![],
            children: vec![],
            children_used: vec![],
            ids: self.ids.clone(),
        };
        for child in node.children().filter(|n| n.is_element()) {
            let child_name = child.attribute("name").map(|n| self.substitute(source, child, n)).transpose()?;
            match child.tag_name().name() {
                "ref" => {
                    let id = self.attr(source, child, "id")?;
                    object.children.push((child_name, Child::Ref { id, at: source.at(child) }));
                }
                t if OBJECT_TAGS.contains(&t) => {
                    let nested = self.object(source, child, nesting + 1)?;
                    object.children.push((child_name, Child::Nested(nested)));
                }
                _ => {
                    let name = child_name.with_context(|| {
                        format!("{}: <{}> has no name attribute", source.at(child), child.tag_name().name())
                    })?;
                    let value = self.value(source, child)?;
                    if object.properties.iter().any(|p| p.name == name) {
                        bail!("{}: {} sets the property '{name}' twice", source.at(child), object.describe());
                    }
                    object.properties.push(Property { name, value, at: source.at(child), used: Cell::new(false) });
                }
            }
        }
        object.children_used = object.children.iter().map(|_| Cell::new(false)).collect();
        let object = Rc::new(object);
        if let Some(id) = id {
            if self.ids.borrow_mut().insert(id.clone(), object.clone()).is_some() {
                bail!("{at}: the id \"{id}\" is used twice");
            }
        }
        Ok(object)
    }

    fn value(&self, source: &Source, node: roxmltree::Node) -> Result<Value> {
        let at = source.at(node);
        let tag = node.tag_name().name();
        let value = || self.attr(source, node, "value");
        Ok(match tag {
            "integer" => Value::Integer(value()?.trim().parse().map_err(|_| {
                anyhow!("{at}: <integer> value '{}' is not an integer", shown(&value().unwrap_or_default()))
            })?),
            "float" => Value::Float(number(&value()?, &at)?),
            "boolean" => Value::Boolean(match value()?.trim() {
                "true" => true,
                "false" => false,
                other => bail!("{at}: <boolean> value '{}' is neither true nor false", shown(other)),
            }),
            "string" => Value::String(value()?),
            "rgb" => {
                let v = numbers(&value()?, &at)?;
                match v.as_slice() {
                    [g] => Value::Rgb(DVec3::splat(*g)),
                    [r, g, b] => Value::Rgb(DVec3::new(*r, *g, *b)),
                    _ => bail!("{at}: <rgb> needs 1 or 3 numbers, got {}", v.len()),
                }
            }
            "spectrum" => {
                if node.attribute("filename").is_some() {
                    bail!("{at}: <spectrum filename=...> is not supported (give the values inline)");
                }
                Value::Spectrum(spectrum(&value()?, &at)?)
            }
            "point" | "vector" => {
                let v = match node.attribute("value") {
                    Some(_) => triple(&value()?, &at)?,
                    None => self.xyz(source, node, 0.0)?,
                };
                if tag == "point" {
                    Value::Point(v)
                } else {
                    Value::Vector(v)
                }
            }
            "transform" => Value::Transform(self.transform(source, node)?),
            other => bail!("{at}: <{other}> is not supported"),
        })
    }

    /// The operations of a `<transform>`, each applied after the ones before it (Mitsuba's order:
    /// `<translate/><rotate/>` translates first).
    fn transform(&self, source: &Source, node: roxmltree::Node) -> Result<DMat4> {
        let mut m = DMat4::IDENTITY;
        for op in node.children().filter(|n| n.is_element()) {
            let at = source.at(op);
            let step = match op.tag_name().name() {
                "translate" => DMat4::from_translation(match op.attribute("value") {
                    Some(_) => triple(&self.attr(source, op, "value")?, &at)?,
                    None => self.xyz(source, op, 0.0)?,
                }),
                "scale" => {
                    let s = match op.attribute("value") {
                        Some(_) => match numbers(&self.attr(source, op, "value")?, &at)?.as_slice() {
                            [s] => DVec3::splat(*s),
                            [x, y, z] => DVec3::new(*x, *y, *z),
                            other => bail!("{at}: <scale value> needs 1 or 3 numbers, got {}", other.len()),
                        },
                        None => self.xyz(source, op, 1.0)?,
                    };
                    DMat4::from_scale(s)
                }
                "rotate" => {
                    let axis = match op.attribute("value") {
                        Some(_) => triple(&self.attr(source, op, "value")?, &at)?,
                        None => self.xyz(source, op, 0.0)?,
                    };
                    let angle = number(&self.attr(source, op, "angle")?, &at)?;
                    if axis.length() == 0.0 {
                        bail!("{at}: <rotate> has no axis (x, y, z all zero)");
                    }
                    DMat4::from_axis_angle(axis.normalize(), angle.to_radians())
                }
                "matrix" => {
                    let v = numbers(&self.attr(source, op, "value")?, &at)?;
                    match v.len() {
                        // Row-major as written.
                        16 => DMat4::from_cols_slice(&v).transpose(),
                        9 => DMat4::from_mat3(glam::DMat3::from_cols_slice(&v).transpose()),
                        n => bail!("{at}: <matrix> needs 16 (or 9) numbers, got {n}"),
                    }
                }
                "lookat" => {
                    let origin = triple(&self.attr(source, op, "origin")?, &at)?;
                    let target = triple(&self.attr(source, op, "target")?, &at)?;
                    let up = triple(
                        &self
                            .attr(source, op, "up")
                            .with_context(|| format!("{at}: <lookat> without up is not supported"))?,
                        &at,
                    )?;
                    look_at(origin, target, up).with_context(|| format!("{at}: <lookat>"))?
                }
                other => {
                    bail!("{at}: <{other}> is not a transform operation (translate, rotate, scale, matrix, lookat)")
                }
            };
            m = step * m;
        }
        if !m.is_finite() {
            bail!("{}: the transform is not finite", source.at(node));
        }
        Ok(m)
    }

    /// The x, y and z attributes, each `default` when absent.
    fn xyz(&self, source: &Source, node: roxmltree::Node, default: f64) -> Result<DVec3> {
        let at = source.at(node);
        let axis = |a: &str| -> Result<f64> {
            match node.attribute(a) {
                Some(v) => number(&self.substitute(source, node, v)?, &at),
                None => Ok(default),
            }
        };
        Ok(DVec3::new(axis("x")?, axis("y")?, axis("z")?))
    }

    /// An attribute without `$` substitution (`<default>` itself).
    fn raw_attr<'n>(&self, source: &Source, node: roxmltree::Node<'n, '_>, name: &str) -> Result<&'n str> {
        node.attribute(name)
            .with_context(|| format!("{}: <{}> needs a {name} attribute", source.at(node), node.tag_name().name()))
    }

    /// An attribute with every `$name` parameter substituted.
    fn attr(&self, source: &Source, node: roxmltree::Node, name: &str) -> Result<String> {
        let raw = self.raw_attr(source, node, name)?;
        self.substitute(source, node, raw)
    }

    /// `raw` with every `$name` replaced by its value; the text this makes over the whole scene is
    /// bounded by [`MAX_SUBSTITUTED_BYTES`] (a short value named many times could otherwise fill
    /// the memory).
    fn substitute(&self, source: &Source, node: roxmltree::Node, raw: &str) -> Result<String> {
        if !raw.contains('$') {
            return Ok(raw.to_owned());
        }
        let mut out = String::with_capacity(raw.len());
        let mut rest = raw;
        while let Some(k) = rest.find('$') {
            out.push_str(&rest[..k]);
            let after = &rest[k + 1..];
            let len = after.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(after.len());
            let name = &after[..len];
            let value = self.params.get(name).with_context(|| {
                format!(
                    "{}: ${name} is not a parameter (no <default name=\"{name}\"> before it, nor -D {name}=...)",
                    source.at(node)
                )
            })?;
            if self.substituted.get() + out.len() + value.len() > MAX_SUBSTITUTED_BYTES {
                bail!(
                    "{}: $name substitution makes more than {} of text",
                    source.at(node),
                    crate::input_file::describe_bytes(MAX_SUBSTITUTED_BYTES as u64)
                );
            }
            out.push_str(value);
            rest = &after[len..];
        }
        out.push_str(rest);
        self.substituted.set(self.substituted.get() + out.len());
        Ok(out)
    }
}

/// Mitsuba's look-at frame: +z towards the target, +y the up vector made orthogonal, +x = up x dir
/// (to the left of the view).
pub fn look_at(origin: DVec3, target: DVec3, up: DVec3) -> Result<DMat4> {
    let dir = (target - origin).try_normalize().context("origin and target coincide")?;
    let left = up.cross(dir).try_normalize().context("up is parallel to the viewing direction")?;
    let new_up = dir.cross(left);
    Ok(DMat4::from_cols(left.extend(0.0), new_up.extend(0.0), dir.extend(0.0), origin.extend(1.0)))
}

fn number(text: &str, at: &Location) -> Result<f64> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => bail!("{at}: '{}' is not a finite number", shown(text)),
    }
}

/// Numbers separated by commas and/or white space.
fn numbers(text: &str, at: &Location) -> Result<Vec<f64>> {
    text.split(|c: char| c == ',' || c.is_whitespace()).filter(|s| !s.is_empty()).map(|s| number(s, at)).collect()
}

fn triple(text: &str, at: &Location) -> Result<DVec3> {
    match numbers(text, at)?.as_slice() {
        [x, y, z] => Ok(DVec3::new(*x, *y, *z)),
        other => bail!("{at}: '{}' needs 3 numbers, got {}", shown(text), other.len()),
    }
}

/// `0.5` (constant: one pair at wavelength 0) or `400:0.1, 500:0.2, ...`.
fn spectrum(text: &str, at: &Location) -> Result<Vec<(f64, f64)>> {
    if !text.contains(':') {
        return match numbers(text, at)?.as_slice() {
            [v] => Ok(vec![(0.0, *v)]),
            other => {
                bail!("{at}: a <spectrum> value is one number or wavelength:value pairs, got {} numbers", other.len())
            }
        };
    }
    let pairs: Vec<(f64, f64)> = text
        .split(',')
        .map(|pair| {
            let (l, v) =
                pair.split_once(':').with_context(|| format!("{at}: '{}' is not wavelength:value", shown(pair)))?;
            Ok((number(l, at)?, number(v, at)?))
        })
        .collect::<Result<_>>()?;
    if pairs.windows(2).any(|w| w[1].0 <= w[0].0) {
        bail!("{at}: the spectrum's wavelengths must increase");
    }
    Ok(pairs)
}

/// Reading an object's properties and children by name: each read marks what it took, and
/// [`Object::check_all_used`] then refuses whatever the mapping did not understand.
impl Object {
    /// `file:line: <bsdf type="diffuse">: message`.
    pub fn error(&self, message: impl fmt::Display) -> anyhow::Error {
        anyhow!("{}: {}: {message}", self.at, self.describe())
    }

    fn property(&self, name: &str) -> Option<&Property> {
        let p = self.properties.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    fn wrong_type(&self, p: &Property, wanted: &str) -> anyhow::Error {
        anyhow!("{}: {}: '{}' must be {wanted}, got {}", p.at, self.describe(), p.name, value_kind(&p.value))
    }

    pub fn float(&self, name: &str, default: f64) -> Result<f64> {
        Ok(self.float_if_given(name)?.unwrap_or(default))
    }

    pub fn float_if_given(&self, name: &str) -> Result<Option<f64>> {
        match self.property(name) {
            None => Ok(None),
            Some(Property { value: Value::Float(v), .. }) => Ok(Some(*v)),
            Some(Property { value: Value::Integer(v), .. }) => Ok(Some(*v as f64)),
            Some(p) => Err(self.wrong_type(p, "a <float>")),
        }
    }

    pub fn integer(&self, name: &str, default: i64) -> Result<i64> {
        match self.property(name) {
            None => Ok(default),
            Some(Property { value: Value::Integer(v), .. }) => Ok(*v),
            Some(p) => Err(self.wrong_type(p, "an <integer>")),
        }
    }

    pub fn boolean(&self, name: &str, default: bool) -> Result<bool> {
        match self.property(name) {
            None => Ok(default),
            Some(Property { value: Value::Boolean(v), .. }) => Ok(*v),
            Some(p) => Err(self.wrong_type(p, "a <boolean>")),
        }
    }

    pub fn string(&self, name: &str) -> Result<Option<&str>> {
        match self.property(name) {
            None => Ok(None),
            Some(Property { value: Value::String(s), .. }) => Ok(Some(s)),
            Some(p) => Err(self.wrong_type(p, "a <string>")),
        }
    }

    /// A colour: `<rgb>`, a `<float>` or constant `<spectrum>` (grey), or a sampled `<spectrum>`
    /// (reduced to RGB, with the warning `sampled`).
    pub fn color(&self, name: &str, sampled: &mut dyn FnMut(&Location)) -> Result<Option<DVec3>> {
        self.color_read(name, sampled, super::spectrum::to_rgb)
    }

    /// As [`Object::color`], for a reflectance: a sampled spectrum is read under D65, as Mitsuba
    /// reads the spectra of everything but emitters.
    pub fn reflectance_color(&self, name: &str, sampled: &mut dyn FnMut(&Location)) -> Result<Option<DVec3>> {
        self.color_read(name, sampled, super::spectrum::reflectance_to_rgb)
    }

    fn color_read(
        &self,
        name: &str,
        sampled: &mut dyn FnMut(&Location),
        spectrum_to_rgb: fn(&[(f64, f64)]) -> DVec3,
    ) -> Result<Option<DVec3>> {
        if let Some(texture) = self.texture_for(name)? {
            return Err(texture.error(format!("textures ('{name}') are not supported; give an <rgb>")));
        }
        match self.property(name) {
            None => Ok(None),
            Some(Property { value: Value::Rgb(c), .. }) => Ok(Some(*c)),
            Some(Property { value: Value::Float(v), .. }) => Ok(Some(DVec3::splat(*v))),
            Some(Property { value: Value::Spectrum(s), .. }) if s.len() == 1 && s[0].0 == 0.0 => {
                Ok(Some(DVec3::splat(s[0].1)))
            }
            Some(p @ Property { value: Value::Spectrum(s), .. }) => {
                sampled(&p.at);
                Ok(Some(spectrum_to_rgb(s)))
            }
            Some(p) => Err(self.wrong_type(p, "an <rgb>, <float> or <spectrum>")),
        }
    }

    /// A `<point>` or `<vector>`.
    pub fn point(&self, name: &str) -> Result<Option<DVec3>> {
        match self.property(name) {
            None => Ok(None),
            Some(Property { value: Value::Point(v) | Value::Vector(v), .. }) => Ok(Some(*v)),
            Some(p) => Err(self.wrong_type(p, "a <point> or <vector>")),
        }
    }

    pub fn transform(&self, name: &str) -> Result<Option<DMat4>> {
        match self.property(name) {
            None => Ok(None),
            Some(Property { value: Value::Transform(m), .. }) => Ok(Some(*m)),
            Some(p) => Err(self.wrong_type(p, "a <transform>")),
        }
    }

    /// The nested object or the object a `<ref>` names.
    fn resolve(&self, child: &Child) -> Result<Rc<Object>> {
        match child {
            Child::Nested(o) => Ok(o.clone()),
            Child::Ref { id, at } => self
                .ids
                .borrow()
                .get(id)
                .cloned()
                .with_context(|| format!("{at}: <ref id=\"{id}\"> names no object of the scene")),
        }
    }

    /// The nested objects (and `<ref>`s) with element `tag`, marked used.
    pub fn children_tagged(&self, tag: &str) -> Result<Vec<Rc<Object>>> {
        let mut found = vec![];
        for ((_, child), used) in self.children.iter().zip(&self.children_used) {
            let object = self.resolve(child)?;
            if object.tag == tag {
                used.set(true);
                found.push(object);
            }
        }
        Ok(found)
    }

    /// The nested object (or `<ref>`) with element `tag` given for the parameter `name` (a
    /// shape's `interior` medium), marked used.
    pub fn named_child(&self, tag: &str, name: &str) -> Result<Option<Rc<Object>>> {
        for ((child_name, child), used) in self.children.iter().zip(&self.children_used) {
            let object = self.resolve(child)?;
            if object.tag == tag && child_name.as_deref() == Some(name) {
                used.set(true);
                return Ok(Some(object));
            }
        }
        Ok(None)
    }

    /// At most one nested object with element `tag`.
    pub fn child(&self, tag: &str) -> Result<Option<Rc<Object>>> {
        let mut found = self.children_tagged(tag)?;
        match found.len() {
            0 | 1 => Ok(found.pop()),
            n => Err(self.error(format!("has {n} nested <{tag}>s; caustica takes one"))),
        }
    }

    /// A texture given for the parameter `name`, if any, marked used.
    pub fn texture(&self, name: &str) -> Result<Option<Rc<Object>>> {
        for ((child_name, child), used) in self.children.iter().zip(&self.children_used) {
            let object = self.resolve(child)?;
            if child_name.as_deref() == Some(name) && object.tag == "texture" {
                used.set(true);
                return Ok(Some(object));
            }
        }
        Ok(None)
    }

    /// A texture given for the parameter `name`, if any.
    fn texture_for(&self, name: &str) -> Result<Option<Rc<Object>>> {
        for (child_name, child) in &self.children {
            let object = self.resolve(child)?;
            if child_name.as_deref() == Some(name) && object.tag == "texture" {
                return Ok(Some(object));
            }
        }
        Ok(None)
    }

    /// An error naming the first property or nested object nothing read: it is not supported.
    pub fn check_all_used(&self) -> Result<()> {
        if let Some(p) = self.properties.iter().find(|p| !p.used.get()) {
            bail!("{}: {}: the parameter '{}' is not supported", p.at, self.describe(), p.name);
        }
        if let Some(((_, child), _)) = self.children.iter().zip(&self.children_used).find(|(_, used)| !used.get()) {
            let c = self.resolve(child)?;
            let at = match child {
                Child::Ref { at, .. } => at.clone(),
                Child::Nested(_) => c.at.clone(),
            };
            bail!("{at}: {} inside {} is not supported there", c.describe(), self.describe());
        }
        Ok(())
    }
}

fn value_kind(v: &Value) -> &'static str {
    match v {
        Value::Integer(_) => "an <integer>",
        Value::Float(_) => "a <float>",
        Value::Boolean(_) => "a <boolean>",
        Value::String(_) => "a <string>",
        Value::Rgb(_) => "an <rgb>",
        Value::Spectrum(_) => "a <spectrum>",
        Value::Point(_) => "a <point>",
        Value::Vector(_) => "a <vector>",
        Value::Transform(_) => "a <transform>",
    }
}
