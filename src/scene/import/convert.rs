//! `caustica convert`: an imported scene file written out as caustica TOML, which loads to the
//! same `Scene` as the import itself (tests/import.rs checks it).

use super::super::format::{MeshFile, SceneFile};
use anyhow::{Context as _, Result};
use std::path::Path;

/// The TOML of `file`, whose relative paths are relative to `base`, for a file in `output_folder`.
/// The meshes written in the scene (`SceneFile::inline_meshes`) are written into `output_folder`
/// as PLY files named after the scene (`NAME-mesh-K.ply`, replacing any there) and listed in
/// `[[meshes]]`.
pub fn to_toml(file: &SceneFile, base: &Path, output_folder: &Path, name: &str) -> Result<String> {
    let mut value = toml::Value::try_from(file).with_context(|| format!("{name}: writing the scene as TOML"))?;
    let same_folder = match (base_or_dot(base).canonicalize(), base_or_dot(output_folder).canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if !same_folder {
        absolute_paths(&mut value, base);
    }
    let stem = Path::new(name).file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    for (k, mesh) in file.inline_meshes.iter().enumerate() {
        let ply = format!("{stem}-mesh-{k}.ply");
        let path = base_or_dot(output_folder).join(&ply);
        std::fs::write(&path, &mesh.ply)
            .with_context(|| format!("{name}: writing the mesh written at {} as {}", mesh.name, path.display()))?;
        let entry = MeshFile {
            file: ply,
            material: Some(mesh.material.clone()),
            shape_index: None,
            flip_normals: false,
            face_normals: false,
            translate: Default::default(),
            scale: None,
            rotate: Default::default(),
            instances: vec![],
        };
        let entry = toml::Value::try_from(entry).with_context(|| format!("{name}: writing the scene as TOML"))?;
        let table = value.as_table_mut().expect("a scene is a table");
        match table.entry("meshes").or_insert_with(|| toml::Value::Array(vec![])) {
            toml::Value::Array(meshes) => meshes.push(entry),
            _ => unreachable!("meshes is a list"),
        }
    }
    shortest_floats(&mut value);
    drop_empty_lists(&mut value);
    let text = toml::to_string(&value).with_context(|| format!("{name}: writing the scene as TOML"))?;
    Ok(format!("# Converted by caustica from {name}\n\n{text}"))
}

fn base_or_dot(p: &Path) -> &Path {
    if p.as_os_str().is_empty() {
        Path::new(".")
    } else {
        p
    }
}

/// Mesh files, texture images, environment maps and density grids, relative to `base`, made absolute: the TOML
/// lives elsewhere.
fn absolute_paths(value: &mut toml::Value, base: &Path) {
    let absolute = |s: &mut String| {
        let p = Path::new(s.as_str());
        if p.is_relative() {
            let joined = base_or_dot(base).join(p);
            *s = joined.canonicalize().unwrap_or(joined).display().to_string();
        }
    };
    if let Some(meshes) = value.get_mut("meshes").and_then(|m| m.as_array_mut()) {
        for mesh in meshes {
            if let Some(toml::Value::String(s)) = mesh.get_mut("file") {
                absolute(s);
            }
        }
    }
    if let Some(materials) = value.get_mut("materials").and_then(|m| m.as_table_mut()) {
        for (_, material) in materials.iter_mut() {
            for key in ["albedo_texture", "opacity_texture", "normal_texture"] {
                if let Some(toml::Value::String(s)) = material.get_mut(key).and_then(|t| t.get_mut("file")) {
                    absolute(s);
                }
            }
        }
    }
    for key in ["latlong", "octahedral"] {
        if let Some(toml::Value::String(s)) = value.get_mut("environment").and_then(|e| e.get_mut(key)) {
            absolute(s);
        }
    }
    // Media's density grids.
    if let Some(media) = value.get_mut("media").and_then(|m| m.as_array_mut()) {
        for medium in media {
            if let Some(toml::Value::String(s)) = medium.get_mut("density") {
                absolute(s);
            }
        }
    }
}

/// Every number of the file is an f32 widened to f64, which TOML would print with all its f64
/// digits (0.1 as 0.10000000149011612). Printed instead is the shortest decimal that reads back,
/// through f64 as the scene loader reads it, as the same f32.
fn shortest_floats(value: &mut toml::Value) {
    match value {
        toml::Value::Float(v) => {
            let single = *v as f32;
            if let Ok(shorter) = single.to_string().parse::<f64>() {
                if shorter as f32 == single {
                    *v = shorter;
                }
            }
        }
        toml::Value::Array(items) => items.iter_mut().for_each(shortest_floats),
        toml::Value::Table(table) => table.iter_mut().for_each(|(_, v)| shortest_floats(v)),
        _ => {}
    }
}

/// Empty lists (no lights, no instances) are what an absent key means; leaving them out keeps the
/// file to what the scene has.
fn drop_empty_lists(value: &mut toml::Value) {
    if let toml::Value::Table(table) = value {
        table.retain(|_, v| !matches!(v, toml::Value::Array(a) if a.is_empty()));
        table.iter_mut().for_each(|(_, v)| drop_empty_lists(v));
    }
    if let toml::Value::Array(items) = value {
        items.iter_mut().for_each(drop_empty_lists);
    }
}
