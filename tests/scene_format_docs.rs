//! docs/scene-format.md in step with the TOML scene parser: every key the parser accepts, and every
//! name a key of a few fixed values takes (`filter = "tent"`, `type = "spot"`), appears in the
//! document.
//!
//! The keys come from the parser itself. A key it does not know is an error that lists the ones it
//! does ("unknown field `zz`, expected one of `a`, `b`, ..."), so each table of the format is probed
//! with such a key. The scene loader shortens a message to its first 300 characters and says how
//! many it left out, so the full lists are read from the serde structs in src/scene/format.rs and
//! each must rebuild the parser's message exactly: its first 300 characters and its length. A key
//! the parser accepts but this test does not see, and a table it does not probe, fail the test as
//! surely as a key missing from the document.

use caustica::scene::Scene;
use std::collections::BTreeSet;
use std::path::Path;

/// The key (or value) no table accepts.
const UNKNOWN: &str = "zz";

/// How many characters of a parser message the scene loader keeps (src/scene/toml_error.rs).
const MESSAGE_CHARS: usize = 300;

const CAMERA: &str = "[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 1.0, 0.0]\n";

/// What a probe expects the parser to list: the fields of a struct, or the variants of an enum
/// (serde `rename_all = "lowercase"`), both as declared in src/scene/format.rs.
#[derive(Clone, Copy)]
enum Listed {
    Fields(&'static str),
    Variants(&'static str),
}

impl Listed {
    fn item(self) -> &'static str {
        match self {
            Listed::Fields(name) | Listed::Variants(name) => name,
        }
    }
}

/// One document per table of the format (and per key of fixed values), each with `zz` where the
/// parser meets it before anything else it could object to.
fn probes() -> Vec<(Listed, String)> {
    let z = UNKNOWN;
    let after_camera = |table: &str| format!("{CAMERA}{table}");
    vec![
        (Listed::Fields("SceneFile"), format!("{z} = 1\n{CAMERA}")),
        (Listed::Fields("CameraFile"), format!("[camera]\n{z} = 1\n")),
        (Listed::Fields("FilmFile"), after_camera(&format!("[film]\n{z} = 1\n"))),
        (Listed::Fields("IntegratorFile"), after_camera(&format!("[integrator]\n{z} = 1\n"))),
        (Listed::Fields("MaterialFile"), after_camera(&format!("[materials.m]\n{z} = 1\n"))),
        (
            Listed::Fields("AlbedoTextureFile"),
            after_camera(&format!("[materials.m]\nalbedo_texture = {{ {z} = 1 }}\n")),
        ),
        (
            Listed::Fields("ImageTextureFile"),
            after_camera(&format!("[materials.m]\nopacity_texture = {{ {z} = 1 }}\n")),
        ),
        (Listed::Fields("ImageTextureFile"), after_camera(&format!("[materials.m]\nnormal_texture = {{ {z} = 1 }}\n"))),
        (Listed::Fields("SphereFile"), after_camera(&format!("[[spheres]]\n{z} = 1\n"))),
        (Listed::Fields("QuadFile"), after_camera(&format!("[[quads]]\n{z} = 1\n"))),
        (Listed::Fields("TriangleFile"), after_camera(&format!("[[triangles]]\n{z} = 1\n"))),
        (Listed::Fields("MeshFile"), after_camera(&format!("[[meshes]]\n{z} = 1\n"))),
        (
            Listed::Fields("Placement"),
            after_camera(&format!("[[meshes]]\nfile = \"m.ply\"\ninstances = [{{ {z} = 1 }}]\n")),
        ),
        (Listed::Fields("EnvironmentFile"), after_camera(&format!("[environment]\n{z} = 1\n"))),
        (Listed::Variants("LightFile"), after_camera(&format!("[[lights]]\ntype = \"{z}\"\n"))),
        (Listed::Fields("PointLightFile"), after_camera(&format!("[[lights]]\ntype = \"point\"\n{z} = 1\n"))),
        (Listed::Fields("SpotLightFile"), after_camera(&format!("[[lights]]\ntype = \"spot\"\n{z} = 1\n"))),
        (
            Listed::Fields("DirectionalLightFile"),
            after_camera(&format!("[[lights]]\ntype = \"directional\"\n{z} = 1\n")),
        ),
        (Listed::Variants("Filter"), after_camera(&format!("[film]\nfilter = \"{z}\"\n"))),
        (Listed::Variants("Sampler"), after_camera(&format!("[integrator]\nsampler = \"{z}\"\n"))),
        (Listed::Variants("LightSelection"), after_camera(&format!("[integrator]\nlight_selection = \"{z}\"\n"))),
        (Listed::Variants("Microfacet"), after_camera(&format!("[materials.m]\ndistribution = \"{z}\"\n"))),
        (Listed::Fields("MediumFile"), after_camera(&format!("[[media]]\n{z} = 1\n"))),
        (Listed::Variants("MediumKind"), after_camera(&format!("[[media]]\ntype = \"{z}\"\n"))),
        (Listed::Variants("PhaseKind"), after_camera(&format!("[[media]]\nphase = \"{z}\"\n"))),
        (Listed::Variants("MaterialKind"), after_camera(&format!("[materials.m]\ntype = \"{z}\"\n"))),
        (
            Listed::Variants("Encoding"),
            after_camera(&format!("[materials.m]\nopacity_texture = {{ encoding = \"{z}\" }}\n")),
        ),
    ]
}

fn repo_file(path: &str) -> String {
    let full = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(&full).unwrap_or_else(|e| panic!("{}: {e}", full.display()))
}

/// The lines of `item` (`pub struct NAME {` or `pub enum NAME {`) in `source`, up to its closing brace.
fn body<'a>(source: &'a str, keyword: &str, item: &str) -> Vec<&'a str> {
    let opening = format!("pub {keyword} {item} {{");
    let mut lines = source.lines().skip_while(|line| line.trim() != opening);
    assert!(lines.next().is_some(), "src/scene/format.rs has no `{opening}`");
    lines.take_while(|line| *line != "}").collect()
}

/// The keys of a struct as serde reads them: its fields, less those marked `#[serde(skip)]`, by
/// the names `#[serde(rename = "...")]` gives them.
fn fields(source: &str, item: &str) -> Vec<String> {
    let mut names = vec![];
    let mut skipped = false;
    let mut renamed = None;
    for line in body(source, "struct", item) {
        let line = line.trim();
        if line.starts_with("#[serde(")
            && (line.contains("skip)") || line.contains("skip,") || line.contains("skip_deserializing"))
        {
            skipped = true;
        } else if let Some(rest) = line.strip_prefix("#[serde(").and_then(|rest| rest.split_once("rename = \"")) {
            renamed = rest.1.split('"').next().map(str::to_owned);
        } else if let Some(field) = line.strip_prefix("pub ").and_then(|rest| rest.split_once(':')) {
            if !skipped {
                names.push(renamed.take().unwrap_or_else(|| field.0.to_owned()));
            }
            skipped = false;
            renamed = None;
        }
    }
    names
}

/// The names of an enum's variants as serde reads them (`rename_all = "lowercase"`).
fn variants(source: &str, item: &str) -> Vec<String> {
    body(source, "enum", item)
        .iter()
        .map(|line| line.trim())
        .filter(|line| line.starts_with(|c: char| c.is_ascii_uppercase()))
        .map(|line| line.split(|c: char| !c.is_ascii_alphanumeric()).next().unwrap().to_lowercase())
        .collect()
}

/// serde's message for an unknown key or value, listing `names` as serde's `OneOf` does.
fn serde_message(listed: Listed, names: &[String]) -> String {
    let what = match listed {
        Listed::Fields(_) => "field",
        Listed::Variants(_) => "variant",
    };
    let quoted: Vec<String> = names.iter().map(|name| format!("`{name}`")).collect();
    let expected = match quoted.as_slice() {
        [] => panic!("{} lists nothing", listed.item()),
        [one] => one.clone(),
        [a, b] => format!("{a} or {b}"),
        all => format!("one of {}", all.join(", ")),
    };
    format!("unknown {what} `{UNKNOWN}`, expected {expected}")
}

/// The parser's message for `document` as the scene loader reports it: the text it kept and how
/// many characters it left out.
fn parser_message(document: &str) -> (String, usize) {
    let error = match Scene::parse(document, "probe.toml", Path::new(".")) {
        Ok(_) => panic!("the parser accepted a key or value it cannot know:\n{document}"),
        Err(e) => format!("{e:#}"),
    };
    let start = error.find("unknown ").unwrap_or_else(|| panic!("no `unknown ...` in:\n{error}\nfor:\n{document}"));
    let line = error[start..].lines().next().unwrap();
    if let Some((kept, rest)) = line.split_once("… (") {
        let left_out = rest.split(' ').next().unwrap().parse().unwrap();
        (kept.to_owned(), left_out)
    } else {
        let message = line.find(" (key ").map_or(line, |end| &line[..end]);
        (message.to_owned(), 0)
    }
}

/// Whether `doc` mentions `name` as a key or a value: `` `name` ``, `"name"`, `name = ` (as written
/// in a TOML example), or a table `[name]`, `[[name]]`, `[name.`.
fn documented(doc: &str, name: &str) -> bool {
    let plain =
        [format!("`{name}`"), format!("\"{name}\""), format!("[{name}]"), format!("[[{name}]]"), format!("[{name}.")];
    if plain.iter().any(|form| doc.contains(form.as_str())) {
        return true;
    }
    let assignment = format!("{name} =");
    doc.match_indices(&assignment)
        .any(|(at, _)| doc[..at].chars().next_back().is_none_or(|c| !(c.is_ascii_alphanumeric() || c == '_')))
}

#[test]
fn every_key_the_parser_accepts_is_in_docs_scene_format() {
    let source = repo_file("src/scene/format.rs");
    let doc = repo_file("docs/scene-format.md");
    let mut probed = BTreeSet::new();
    let mut missing = vec![];
    for (listed, document) in probes() {
        let names = match listed {
            Listed::Fields(item) => fields(&source, item),
            Listed::Variants(item) => variants(&source, item),
        };
        let full = serde_message(listed, &names);
        let (kept, left_out) = parser_message(&document);
        let rebuilt: String = full.chars().take(MESSAGE_CHARS).collect();
        let rebuilt_left_out = full.chars().count().saturating_sub(MESSAGE_CHARS);
        assert!(
            kept == rebuilt && left_out == rebuilt_left_out,
            "{} in src/scene/format.rs does not rebuild the parser's message:\n  parser: {kept} \
             (+{left_out} characters)\n  format.rs: {full}\nfor:\n{document}",
            listed.item()
        );
        probed.insert(listed.item());
        for name in names {
            if !documented(&doc, &name) {
                missing.push(format!("{name} ({})", listed.item()));
            }
        }
    }
    // Every type the parser reads a table or value into is probed above.
    let mut read = BTreeSet::new();
    let mut lines = source.lines();
    while let Some(line) = lines.next() {
        if line.starts_with("#[derive(") && line.contains("Deserialize") {
            let item = lines.by_ref().find(|l| l.starts_with("pub struct ") || l.starts_with("pub enum ")).unwrap();
            read.insert(item.split_whitespace().nth(2).unwrap().trim_end_matches('{').to_owned());
        }
    }
    let unprobed: Vec<_> = read.iter().filter(|item| !probed.contains(item.as_str())).collect();
    assert!(unprobed.is_empty(), "src/scene/format.rs reads these, which this test does not probe: {unprobed:?}");
    assert!(missing.is_empty(), "docs/scene-format.md does not mention these keys or values: {missing:?}");
}
