//! pbrt-v4 directives read into a [`Model`]: the transformation and attribute state of pbrt's
//! scene builder is applied here (the current transformation matrix, `ReverseOrientation`, the
//! current material and area light, named coordinate systems, `ObjectBegin` definitions), so that
//! every shape and light comes out with the state it was declared in. What the directives mean
//! for caustica is `mapping.rs`'s business; this module only reads them faithfully, in pbrt's
//! order, remembering where each was written.

use super::super::{shown, Location};
use super::params::{Directive, Param, Values};
use super::tokens::{Token, Tokens};
use crate::input_file::{InputFiles, InputKind};
use anyhow::{anyhow, bail, Context as _, Result};
use glam::{DMat4, DVec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// An `Include`/`Import` chain deeper than this is a cycle (or a hostile file).
const MAX_INCLUDE_DEPTH: usize = 16;

/// The most scene text read in all, includes together: each file has its own cap
/// (`InputKind::Scene`), and this bounds a file that includes another many times over.
const MAX_TOTAL_BYTES: usize = 256 << 20;
/// The most files read in all, each include counted as often as it is read: empty files would
/// otherwise escape MAX_TOTAL_BYTES, however often they are included.
const MAX_FILES: usize = 4096;

/// The material a shape was declared with.
#[derive(Clone, Debug)]
pub enum MaterialRef {
    /// pbrt's default, diffuse with reflectance 0.5.
    Default,
    /// A `Material` directive.
    Anonymous(Rc<MaterialDef>),
    /// A `NamedMaterial`, resolved once the whole scene is read (pbrt allows later definitions).
    Named(String, Location),
}

/// A material: its type (`diffuse`, ...) and parameters; for `MakeNamedMaterial`, `kind` is the
/// name and `ty` its `"string type"`.
#[derive(Debug)]
pub struct MaterialDef {
    pub ty: String,
    pub directive: Directive,
}

/// A `Shape` with the graphics state it was declared in.
#[derive(Clone, Debug)]
pub struct ShapeUse {
    pub shape: Rc<Directive>,
    /// Object to world (within an `ObjectBegin`: to the world the instance is placed in).
    pub transform: DMat4,
    pub reverse_orientation: bool,
    pub material: MaterialRef,
    pub area_light: Option<Rc<Directive>>,
}

/// `Texture "name" "spectrum" "class" ...`.
#[derive(Debug)]
pub struct TextureDef {
    pub name: String,
    /// `spectrum` or `float`.
    pub value_type: String,
    /// The class (constant, scale, mix, checkerboard, imagemap, ...) as the directive's kind.
    pub class: Directive,
}

/// `ObjectInstance "name"` with the transformation it was placed by.
#[derive(Debug)]
pub struct InstanceUse {
    pub name: String,
    pub at: Location,
    pub transform: DMat4,
}

/// `Camera` with the transformation current when it was declared (camera from world).
#[derive(Debug)]
pub struct CameraUse {
    pub camera: Directive,
    pub camera_from_world: DMat4,
}

/// The scene as pbrt's builder sees it once every file is read.
#[derive(Default, Debug)]
pub struct Model {
    pub camera: Option<CameraUse>,
    pub film: Option<Directive>,
    pub sampler: Option<Directive>,
    pub integrator: Option<Directive>,
    pub filter: Option<Directive>,
    pub named_materials: HashMap<String, Rc<MaterialDef>>,
    /// By (value type, name): spectrum and float textures have separate names in pbrt.
    pub textures: HashMap<(String, String), Rc<TextureDef>>,
    /// `LightSource`s with their object-to-world transformation.
    pub lights: Vec<(Directive, DMat4)>,
    pub shapes: Vec<ShapeUse>,
    /// `ObjectBegin` definitions: their shapes and where they were begun.
    pub objects: HashMap<String, (Vec<ShapeUse>, Location)>,
    pub instances: Vec<InstanceUse>,
}

/// Reads the scene at `path` and everything it includes.
pub fn read(files: &InputFiles, path: &Path) -> Result<Model> {
    let mut reader = Reader {
        files,
        // pbrt resolves every relative file name against the main file's folder.
        base: path.parent().map(Path::to_path_buf).unwrap_or_default(),
        model: Model::default(),
        state: GraphicsState {
            ctm: DMat4::IDENTITY,
            reverse_orientation: false,
            material: MaterialRef::Default,
            area_light: None,
        },
        stack: vec![],
        coordinate_systems: HashMap::new(),
        in_world: false,
        object: None,
        depth: 0,
        bytes: 0,
        files_read: 0,
    };
    reader.file(path)?;
    if let Some((_, kind, at)) = reader.stack.last() {
        bail!("{at}: this {kind} is never ended");
    }
    if !reader.in_world {
        bail!("{}: the scene has no WorldBegin", path.display());
    }
    Ok(reader.model)
}

#[derive(Clone)]
struct GraphicsState {
    ctm: DMat4,
    reverse_orientation: bool,
    material: MaterialRef,
    area_light: Option<Rc<Directive>>,
}

struct Reader<'a> {
    files: &'a InputFiles,
    base: PathBuf,
    model: Model,
    state: GraphicsState,
    /// Saved states: AttributeBegin, TransformBegin or ObjectBegin, and where.
    stack: Vec<(GraphicsState, &'static str, Location)>,
    coordinate_systems: HashMap<String, DMat4>,
    in_world: bool,
    /// The `ObjectBegin` being defined: its name, shapes and where it began.
    object: Option<(String, Vec<ShapeUse>, Location)>,
    depth: usize,
    bytes: usize,
    files_read: usize,
}

/// Directives that set up the render, allowed only before `WorldBegin`.
const OPTIONS: [&str; 6] = ["Camera", "Film", "Sampler", "Integrator", "PixelFilter", "Accelerator"];

impl Reader<'_> {
    fn file(&mut self, path: &Path) -> Result<()> {
        self.files_read += 1;
        if self.files_read > MAX_FILES {
            bail!("{}: the scene reads more than {MAX_FILES} files through includes", path.display());
        }
        let text = self.files.read_to_string(path, InputKind::Scene)?;
        self.bytes += text.len();
        if self.bytes > MAX_TOTAL_BYTES {
            bail!(
                "{}: the scene and its includes hold more than {} MiB of text",
                path.display(),
                MAX_TOTAL_BYTES >> 20
            );
        }
        let mut tokens = Tokens::new(&text, Rc::from(path.display().to_string().as_str()));
        while let Some((token, at)) = tokens.next()? {
            let Token::Word(name) = token else { bail!("{at}: expected a directive, found {}", token.describe()) };
            self.directive(&name, at, &mut tokens)?;
        }
        Ok(())
    }

    fn directive(&mut self, name: &str, at: Location, t: &mut Tokens) -> Result<()> {
        if OPTIONS.contains(&name) && self.in_world {
            bail!("{at}: {name} must come before WorldBegin");
        }
        let world_only = matches!(
            name,
            "Shape"
                | "Material"
                | "MakeNamedMaterial"
                | "NamedMaterial"
                | "Texture"
                | "LightSource"
                | "AreaLightSource"
                | "ObjectBegin"
                | "ObjectEnd"
                | "ObjectInstance"
        );
        if world_only && !self.in_world {
            bail!("{at}: {name} must come after WorldBegin");
        }
        match name {
            "Translate" => {
                let v = numbers(t, &at, 3, name)?;
                self.concat(DMat4::from_translation(DVec3::new(v[0], v[1], v[2])));
            }
            "Scale" => {
                let v = numbers(t, &at, 3, name)?;
                self.concat(DMat4::from_scale(DVec3::new(v[0], v[1], v[2])));
            }
            "Rotate" => {
                let v = numbers(t, &at, 4, name)?;
                let axis = DVec3::new(v[1], v[2], v[3])
                    .try_normalize()
                    .ok_or_else(|| anyhow!("{at}: Rotate about a zero axis"))?;
                self.concat(DMat4::from_axis_angle(axis, v[0].to_radians()));
            }
            "LookAt" => {
                let v = numbers(t, &at, 9, name)?;
                let (eye, look, up) =
                    (DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]), DVec3::new(v[6], v[7], v[8]));
                self.concat(look_at(eye, look, up).map_err(|e| anyhow!("{at}: LookAt: {e}"))?);
            }
            "Transform" | "ConcatTransform" => {
                let v = bracketed_numbers(t, &at, 16, name)?;
                // pbrt lists the matrix column by column (the translation is in 12, 13, 14).
                let m = DMat4::from_cols_slice(&v);
                if name == "Transform" {
                    self.state.ctm = m;
                } else {
                    self.concat(m);
                }
            }
            "Identity" => self.state.ctm = DMat4::IDENTITY,
            "CoordinateSystem" => {
                let n = string(t, &at, name)?;
                self.coordinate_systems.insert(n, self.state.ctm);
            }
            "CoordSysTransform" => {
                let n = string(t, &at, name)?;
                self.state.ctm = *self
                    .coordinate_systems
                    .get(&n)
                    .ok_or_else(|| anyhow!("{at}: CoordSysTransform: no coordinate system named \"{n}\""))?;
            }
            "ReverseOrientation" => self.state.reverse_orientation = !self.state.reverse_orientation,
            "AttributeBegin" => self.push("AttributeBegin", at),
            "TransformBegin" => self.push("TransformBegin", at),
            "AttributeEnd" => self.pop("AttributeBegin", &at)?,
            "TransformEnd" => self.pop("TransformBegin", &at)?,
            "WorldBegin" => {
                if self.in_world {
                    bail!("{at}: a second WorldBegin");
                }
                self.in_world = true;
                self.state.ctm = DMat4::IDENTITY;
                self.coordinate_systems.insert("world".into(), DMat4::IDENTITY);
            }
            // pbrt-v3's end of the scene; pbrt-v4 ends it with the file.
            "WorldEnd" => {}
            "Camera" => {
                let camera = directive(t, at.clone(), "Camera")?;
                if self.model.camera.is_some() {
                    bail!("{at}: a second Camera");
                }
                let camera_from_world = self.state.ctm;
                let determinant = camera_from_world.determinant().abs();
                if determinant.is_nan() || determinant <= 1e-12 {
                    bail!("{at}: Camera: the current transformation is not invertible");
                }
                self.coordinate_systems.insert("camera".into(), camera_from_world.inverse());
                self.model.camera = Some(CameraUse { camera, camera_from_world });
            }
            "Film" | "Sampler" | "Integrator" | "PixelFilter" => {
                let d = directive(t, at.clone(), static_name(name))?;
                let slot = match name {
                    "Film" => &mut self.model.film,
                    "Sampler" => &mut self.model.sampler,
                    "Integrator" => &mut self.model.integrator,
                    _ => &mut self.model.filter,
                };
                if slot.is_some() {
                    bail!("{at}: a second {name}");
                }
                *slot = Some(d);
            }
            // How pbrt builds its acceleration structure: nothing to do with the image.
            "Accelerator" => {
                directive(t, at, "Accelerator")?;
            }
            "ColorSpace" => {
                let space = string(t, &at, name)?;
                if space != "srgb" {
                    bail!("{at}: ColorSpace \"{space}\" is not supported (caustica renders linear sRGB)");
                }
            }
            "Material" => {
                let d = directive(t, at, "Material")?;
                self.state.material = MaterialRef::Anonymous(Rc::new(MaterialDef { ty: d.kind.clone(), directive: d }));
            }
            "MakeNamedMaterial" => {
                let d = directive(t, at.clone(), "MakeNamedMaterial")?;
                let ty = d.string("type")?.ok_or_else(|| d.error("needs a \"string type\""))?.to_owned();
                let name = d.kind.clone();
                if self.model.named_materials.insert(name.clone(), Rc::new(MaterialDef { ty, directive: d })).is_some()
                {
                    bail!("{at}: the material \"{name}\" is defined twice");
                }
            }
            "NamedMaterial" => {
                let n = string(t, &at, name)?;
                self.state.material = MaterialRef::Named(n, at);
            }
            "Texture" => {
                let tex_name = string(t, &at, name)?;
                let value_type = string(t, &at, name)?;
                if !matches!(value_type.as_str(), "spectrum" | "float") {
                    bail!("{at}: Texture \"{tex_name}\": the value type is \"spectrum\" or \"float\", not \"{value_type}\"");
                }
                let class = directive(t, at.clone(), "Texture")?;
                let key = (value_type.clone(), tex_name.clone());
                if self
                    .model
                    .textures
                    .insert(key, Rc::new(TextureDef { name: tex_name.clone(), value_type, class }))
                    .is_some()
                {
                    bail!("{at}: the texture \"{tex_name}\" is defined twice");
                }
            }
            "LightSource" => {
                let d = directive(t, at.clone(), "LightSource")?;
                if self.object.is_some() {
                    bail!("{at}: a LightSource inside ObjectBegin (pbrt does not instance lights)");
                }
                self.model.lights.push((d, self.state.ctm));
            }
            "AreaLightSource" => {
                let d = directive(t, at, "AreaLightSource")?;
                self.state.area_light = Some(Rc::new(d));
            }
            "Shape" => {
                let d = directive(t, at.clone(), "Shape")?;
                let shape = ShapeUse {
                    shape: Rc::new(d),
                    transform: self.state.ctm,
                    reverse_orientation: self.state.reverse_orientation,
                    material: self.state.material.clone(),
                    area_light: self.state.area_light.clone(),
                };
                match &mut self.object {
                    Some(_) if shape.area_light.is_some() => {
                        bail!("{at}: an area light inside ObjectBegin (pbrt does not instance area lights)")
                    }
                    Some((_, shapes, _)) => shapes.push(shape),
                    None => self.model.shapes.push(shape),
                }
            }
            "ObjectBegin" => {
                let n = string(t, &at, name)?;
                if let Some((outer, _, begun)) = &self.object {
                    bail!("{at}: ObjectBegin \"{n}\" inside ObjectBegin \"{outer}\" of {begun}");
                }
                self.push("ObjectBegin", at.clone());
                self.object = Some((n, vec![], at));
            }
            "ObjectEnd" => {
                let Some((n, shapes, begun)) = self.object.take() else { bail!("{at}: ObjectEnd without ObjectBegin") };
                self.pop("ObjectBegin", &at)?;
                if self.model.objects.insert(n.clone(), (shapes, begun)).is_some() {
                    bail!("{at}: the object \"{n}\" is defined twice");
                }
            }
            "ObjectInstance" => {
                let n = string(t, &at, name)?;
                if self.object.is_some() {
                    bail!("{at}: ObjectInstance inside ObjectBegin (nested instancing is not supported)");
                }
                self.model.instances.push(InstanceUse { name: n, at, transform: self.state.ctm });
            }
            "Include" | "Import" => {
                let file = string(t, &at, name)?;
                let path = self.resolve(&file);
                if self.depth >= MAX_INCLUDE_DEPTH {
                    bail!(
                        "{at}: {name} \"{file}\": includes nest more than {MAX_INCLUDE_DEPTH} deep (an include cycle?)"
                    );
                }
                // Import is Include whose graphics state does not leak out (pbrt-v4 reads it in
                // parallel, so its state changes cannot reach the including file).
                let saved = (name == "Import").then(|| (self.state.clone(), self.stack.len()));
                self.depth += 1;
                self.file(&path).with_context(|| format!("{at}: in the {name} of {}", path.display()))?;
                self.depth -= 1;
                if let Some((state, height)) = saved {
                    if self.stack.len() != height {
                        bail!("{at}: Import \"{file}\" leaves an AttributeBegin open");
                    }
                    self.state = state;
                }
            }
            "MediumInterface" => {
                let mut names = vec![string(t, &at, name)?];
                if let Some((Token::Quoted(_), _)) = t.peek()? {
                    names.push(string(t, &at, name)?);
                }
                if names.iter().any(|n| !n.is_empty()) {
                    bail!("{at}: MediumInterface: participating media are not supported");
                }
            }
            "MakeNamedMedium" => bail!("{at}: MakeNamedMedium: participating media are not supported"),
            "Attribute" => bail!("{at}: Attribute (default parameters for a kind of directive) is not supported"),
            "Option" => bail!("{at}: Option is not supported"),
            "ActiveTransform" | "TransformTimes" => {
                bail!("{at}: {name}: animated transformations (motion blur) are not supported")
            }
            _ => bail!("{at}: unknown directive '{}'", shown(name)),
        }
        Ok(())
    }

    /// Applies `m` after the current transformation, as pbrt's transform directives do.
    fn concat(&mut self, m: DMat4) {
        self.state.ctm *= m;
    }

    fn push(&mut self, kind: &'static str, at: Location) {
        self.stack.push((self.state.clone(), kind, at));
    }

    /// Ends the innermost block, which must be a `kind`: AttributeEnd restores the whole state,
    /// TransformEnd only the transformation.
    fn pop(&mut self, kind: &'static str, at: &Location) -> Result<()> {
        let ender = match kind {
            "AttributeBegin" => "AttributeEnd",
            "TransformBegin" => "TransformEnd",
            _ => "ObjectEnd",
        };
        match self.stack.pop() {
            Some((state, begun, _)) if begun == kind => {
                if kind == "TransformBegin" {
                    self.state.ctm = state.ctm;
                } else {
                    self.state = state;
                }
                Ok(())
            }
            Some((_, begun, begun_at)) => bail!("{at}: {ender} ends the {begun} of {begun_at}"),
            None => bail!("{at}: {ender} without {kind}"),
        }
    }

    fn resolve(&self, name: &str) -> PathBuf {
        let p = Path::new(name);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.base.join(p)
        }
    }
}

fn static_name(name: &str) -> &'static str {
    match name {
        "Film" => "Film",
        "Sampler" => "Sampler",
        "Integrator" => "Integrator",
        _ => "PixelFilter",
    }
}

/// pbrt's look-at, as world-from-camera inverted: camera +z towards `look`, +y the up vector
/// made orthogonal, +x = up x dir.
fn look_at(eye: DVec3, look: DVec3, up: DVec3) -> Result<DMat4> {
    let dir = (look - eye).try_normalize().context("the eye and the point looked at coincide")?;
    let right = up.normalize_or_zero().cross(dir).try_normalize().context("up is parallel to the viewing direction")?;
    let new_up = dir.cross(right);
    let world_from_camera = DMat4::from_cols(right.extend(0.0), new_up.extend(0.0), dir.extend(0.0), eye.extend(1.0));
    Ok(world_from_camera.inverse())
}

fn number(token: &Token, at: &Location, what: &str) -> Result<f64> {
    match token {
        Token::Word(w) => match w.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => bail!("{at}: {what}: '{}' is not a finite number", shown(w)),
        },
        other => bail!("{at}: {what}: expected a number, found {}", other.describe()),
    }
}

/// `count` bare numbers after a directive.
fn numbers(t: &mut Tokens, at: &Location, count: usize, what: &str) -> Result<Vec<f64>> {
    (0..count)
        .map(|_| match t.next()? {
            Some((token, at)) => number(&token, &at, what),
            None => bail!("{at}: {what} needs {count} numbers; the file ends first"),
        })
        .collect()
}

/// `count` numbers, in brackets or not.
fn bracketed_numbers(t: &mut Tokens, at: &Location, count: usize, what: &str) -> Result<Vec<f64>> {
    if !matches!(t.peek()?, Some((Token::Open, _))) {
        return numbers(t, at, count, what);
    }
    t.next()?;
    let v = numbers(t, at, count, what)?;
    match t.next()? {
        Some((Token::Close, _)) => Ok(v),
        Some((other, at)) => bail!("{at}: {what} takes {count} numbers, found {} after them", other.describe()),
        None => bail!("{at}: {what}: the file ends before ']'"),
    }
}

fn string(t: &mut Tokens, at: &Location, what: &str) -> Result<String> {
    match t.next()? {
        Some((Token::Quoted(s), _)) => Ok(s),
        Some((other, at)) => bail!("{at}: {what} needs a quoted string, found {}", other.describe()),
        None => bail!("{at}: {what} needs a quoted string; the file ends first"),
    }
}

/// A directive's quoted type and its parameter list.
fn directive(t: &mut Tokens, at: Location, name: &'static str) -> Result<Directive> {
    let kind = string(t, &at, name)?;
    let mut params: Vec<Param> = vec![];
    // The names given so far: a set, so that a directive of very many parameters is not quadratic.
    let mut names = std::collections::HashSet::new();
    while let Some((Token::Quoted(_), _)) = t.peek()? {
        let Some((Token::Quoted(declaration), param_at)) = t.next()? else { unreachable!("peeked a quoted string") };
        let words: Vec<&str> = declaration.split_whitespace().collect();
        let [ty, param_name] = words[..] else {
            bail!(
                "{param_at}: {name} \"{}\": \"{}\" is not a parameter declaration (\"type name\")",
                shown(&kind),
                shown(&declaration)
            )
        };
        let values = values(t, &param_at, ty, &declaration)?;
        if !names.insert(param_name.to_owned()) {
            bail!("{param_at}: {name} \"{kind}\": the parameter '{param_name}' is given twice");
        }
        params.push(Param::new(ty.to_owned(), param_name.to_owned(), values, param_at)?);
    }
    Ok(Directive { directive: name, kind, at, params })
}

/// A parameter's value: one token, or a bracketed list, read as the declared type needs.
fn values(t: &mut Tokens, at: &Location, ty: &str, declaration: &str) -> Result<Values> {
    let mut tokens = vec![];
    match t.next()? {
        Some((Token::Open, _)) => loop {
            match t.next()? {
                Some((Token::Close, _)) => break,
                Some((Token::Open, at)) => bail!("{at}: \"{declaration}\": '[' inside a list"),
                Some((token, at)) => tokens.push((token, at)),
                None => bail!("{at}: \"{declaration}\": the file ends before the list's ']'"),
            }
        },
        Some((Token::Close, at)) => bail!("{at}: \"{declaration}\": ']' without '['"),
        Some(token) => tokens.push(token),
        None => bail!("{at}: \"{declaration}\" has no value; the file ends first"),
    }
    if ty == "bool" {
        let bools = tokens.iter().map(|(token, at)| match token {
            Token::Word(w) | Token::Quoted(w) if w == "true" => Ok(true),
            Token::Word(w) | Token::Quoted(w) if w == "false" => Ok(false),
            other => bail!("{at}: \"{declaration}\": expected true or false, found {}", other.describe()),
        });
        return Ok(Values::Bools(bools.collect::<Result<_>>()?));
    }
    if tokens.iter().any(|(token, _)| matches!(token, Token::Quoted(_))) {
        let strings = tokens.into_iter().map(|(token, at)| match token {
            Token::Quoted(s) => Ok(s),
            other => bail!("{at}: \"{declaration}\": strings and numbers mixed in one list ({})", other.describe()),
        });
        return Ok(Values::Strings(strings.collect::<Result<_>>()?));
    }
    let numbers = tokens.iter().map(|(token, at)| number(token, at, &format!("\"{declaration}\"")));
    Ok(Values::Numbers(numbers.collect::<Result<_>>()?))
}
