//! tests/mutations.toml, the list scripts/mutate.py applies (docs/testing.md), stays true to the
//! code: every mutation's text occurs exactly once in its file, so none silently stops applying
//! when the code moves on, and the list keeps covering every part of the renderer.

use std::collections::BTreeMap;
use std::path::Path;

#[test]
fn every_mutation_applies_to_the_code_as_it_is() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("tests/mutations.toml")).expect("tests/mutations.toml");
    let list: toml::Table = toml::from_str(&text).expect("tests/mutations.toml parses");
    let mutations = list["mutation"].as_array().expect("[[mutation]] tables");
    let mut per_area = BTreeMap::<String, usize>::new();
    // Every stale text is named at once, so one edit of the code costs one edit of the list.
    let mut stale = Vec::new();
    for m in mutations {
        let field = |key: &str| {
            m.get(key).and_then(|v| v.as_str()).unwrap_or_else(|| panic!("mutation {m:?} lacks '{key}'")).to_owned()
        };
        let (id, file, find, replace) = (field("id"), field("file"), field("find"), field("replace"));
        field("bug");
        assert!(m.get("tests").and_then(|t| t.as_array()).is_some_and(|t| !t.is_empty()), "{id}: no tests named");
        let code = std::fs::read_to_string(root.join(&file)).unwrap_or_else(|e| panic!("{id}: {file}: {e}"));
        let found = code.matches(&find).count();
        if found != 1 {
            stale.push(format!("{id}: its text occurs {found} times in {file}, not once"));
        }
        assert_ne!(find, replace, "{id}: the mutation changes nothing");
        *per_area.entry(field("area")).or_default() += 1;
    }
    assert!(stale.is_empty(), "mutations that no longer apply:\n{}", stale.join("\n"));
    assert!(mutations.len() >= 30, "{} mutations; the list keeps at least 30", mutations.len());
    for area in ["sampling", "materials", "lights", "integrator", "environment", "bvh", "textures"] {
        assert!(per_area.get(area).is_some_and(|&n| n >= 2), "area {area} has {:?} mutations", per_area.get(area));
    }
}
