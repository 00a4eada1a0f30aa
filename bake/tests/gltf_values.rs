//! The glTF loader refuses values the maths downstream would carry to infinity where they
//! enter (docs/FORMATS.md, "The ranges values are read in"), and leaves out an emission it
//! cannot read.

mod gltf_support;

use glam::Vec3;
use gltf_support::*;
use relume_bake::gltf_load::CameraOverride;
use serde_json::{json, Value};

/// Finite values too large for the maths downstream are refused where they enter, naming the
/// item: a light of 3e38 (samples overflowed to infinity), an emission of 1e30, a Phong
/// exponent of 1e30 (infinity times zero in the lobe), an ambient light of 1e30, an
/// environment intensity of 1e30, an MRT grid cell of 1e30 m.
#[test]
fn huge_finite_values_are_refused_where_they_enter() {
    let dir = temp_dir("huge");
    type Spoil = fn(&mut Value);
    let cases: [(&str, Spoil, &str); 6] = [
        ("cornell", |j| j["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = json!(3e38), "exceeds 1e9"),
        (
            "cornell",
            |j| {
                j["extensionsUsed"].as_array_mut().unwrap().push(json!("KHR_materials_emissive_strength"));
                j["materials"][0]["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
                j["materials"][0]["extensions"] = json!({ "KHR_materials_emissive_strength": { "emissiveStrength": 1e30 } });
            },
            "material \"white\"",
        ),
        ("cornell", |j| j["materials"][0]["extras"] = json!({ "relume": { "phong": { "specular": 0.1, "exponent": 1e30 } } }), "past 1e6"),
        ("cornell", |j| j["scenes"][0]["extras"]["relume"]["ambient"] = json!([1e30, 1.0, 1.0]), "0..=1e9"),
        ("fiv-blobs", |j| j["scenes"][0]["extras"]["relume"]["environment"]["intensity"] = json!(1e30), "0..=1e9"),
        ("mrt-maze", |j| j["scenes"][0]["extras"]["relume"]["mrt"]["grid"]["cell"] = json!([1e30, 2.0, 2.0]), "within 1000000 m"),
    ];
    for (k, (name, spoil, words)) in cases.into_iter().enumerate() {
        let (mut json, bin) = read_scene(name);
        spoil(&mut json);
        let line = load_err(&write_scene(&dir, &format!("{name}-{k}"), &json, Some(&bin))).to_string();
        assert!(line.contains(words), "case {k}: {line}");
    }
}

/// An emissive texture is not read: rather than glow uniformly at its factor (its dark parts as
/// its bright ones: ClearCoatTest nearly black but "lit"), the material emits nothing, with a
/// warning, and a scene nothing else lights takes the default rig.
#[test]
fn an_emissive_texture_leaves_the_emission_out_with_a_warning() {
    let dir = temp_dir("emissive-texture");
    let (mut json, bin) = read_scene("occluder-plane");
    json["images"] = json!([{ "uri": "glow.png" }]);
    json["textures"] = json!([{ "source": 0 }]);
    json["materials"][0]["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
    json["materials"][0]["emissiveTexture"] = json!({ "index": 0 });
    let loaded = load_ok(&write_scene(&dir, "x", &json, Some(&bin)));
    assert!(loaded.warnings.iter().any(|w| w.contains("emissiveTexture is not read")), "{:?}", loaded.warnings);
    assert!(loaded.scene.materials.iter().all(|m| m.emission == Vec3::ZERO));
}

/// A vertex or a light past 1e7 m from the origin (a node scaled by 1e30 gave finite but
/// useless coordinates) is refused by item, as is a lights file's light and a camera there.
#[test]
fn coordinates_past_ten_thousand_kilometres_are_refused() {
    let dir = temp_dir("far");
    let (mut json, bin) = read_scene("cornell");
    json["nodes"][0]["scale"] = json!([1e30, 1.0, 1.0]);
    let line = load_err(&write_scene(&dir, "scaled", &json, Some(&bin))).to_string();
    assert!(line.contains("past 1e7 m"), "{line}");
    let (mut json, bin) = read_scene("cornell");
    let light_node = json["nodes"].as_array().unwrap().iter().position(|n| n["extensions"]["KHR_lights_punctual"].is_object()).unwrap();
    json["nodes"][light_node]["translation"] = json!([0.0, 1e30, 0.0]);
    let line = load_err(&write_scene(&dir, "light", &json, Some(&bin))).to_string();
    assert!(line.contains("light") && line.contains("past 1e7 m"), "{line}");
    let error = CameraOverride::parse("eye=0,0,1e30;target=0,0,0").unwrap_err().to_string();
    assert!(error.contains("within 1e7 m"), "{error}");
}
