//! Leaves out of a scene's written document the accessors nothing uses any
//! more (the primitives the LODs replaced) and the buffer bytes only they
//! held, so an export is not its input plus its LODs. Only where every
//! reference to an accessor or a buffer view is known: a document using an
//! extension that may name them (instancing, compression, anything
//! unknown) is left whole.

use serde_json::{Value, json};

/// Extensions known to name no accessor and no buffer view.
fn harmless(extension: &str) -> bool {
    extension.starts_with("KHR_materials_")
        || matches!(
            extension,
            "KHR_texture_transform"
                | "KHR_lights_punctual"
                | "KHR_texture_basisu"
                | "EXT_texture_webp"
                | "MSFT_lod"
                | "KHR_mesh_quantization"
        )
}

/// The array `key` of `v`, mutably (none when absent: indexing mutably
/// would add a `null` the document never had).
fn array<'a>(v: &'a mut Value, key: &str) -> impl Iterator<Item = &'a mut Value> {
    v.get_mut(key)
        .and_then(Value::as_array_mut)
        .into_iter()
        .flatten()
}

/// The values of the object `key` of `v`, mutably.
fn values<'a>(v: &'a mut Value, key: &str) -> impl Iterator<Item = &'a mut Value> {
    v.get_mut(key)
        .and_then(Value::as_object_mut)
        .into_iter()
        .flat_map(|o| o.values_mut())
}

/// Every place of a scene's document that names an accessor.
fn accessor_refs(doc: &mut Value, each: &mut dyn FnMut(&mut Value)) {
    for mesh in array(doc, "meshes") {
        for p in array(mesh, "primitives") {
            values(p, "attributes").for_each(&mut *each);
            if let Some(i) = p.get_mut("indices") {
                each(i);
            }
            for t in array(p, "targets") {
                t.as_object_mut()
                    .into_iter()
                    .flat_map(|o| o.values_mut())
                    .for_each(&mut *each);
            }
        }
    }
    for skin in array(doc, "skins") {
        if let Some(i) = skin.get_mut("inverseBindMatrices") {
            each(i);
        }
    }
    for animation in array(doc, "animations") {
        for s in array(animation, "samplers") {
            for key in ["input", "output"] {
                if let Some(i) = s.get_mut(key) {
                    each(i);
                }
            }
        }
    }
}

/// Every place that names a buffer view.
fn view_refs(doc: &mut Value, each: &mut dyn FnMut(&mut Value)) {
    for a in array(doc, "accessors") {
        if let Some(v) = a.get_mut("bufferView") {
            each(v);
        }
        if let Some(sparse) = a.get_mut("sparse") {
            for part in ["indices", "values"] {
                if let Some(v) = sparse.get_mut(part).and_then(|p| p.get_mut("bufferView")) {
                    each(v);
                }
            }
        }
    }
    for image in array(doc, "images") {
        if let Some(v) = image.get_mut("bufferView") {
            each(v);
        }
    }
}

/// A walk over every place of a document that names one kind of object.
type Refs = fn(&mut Value, &mut dyn FnMut(&mut Value));

/// Keeps the entries of `doc[key]` that the references `refs` visits
/// name, renumbering those references.
fn keep_used(doc: &mut Value, key: &str, refs: Refs) {
    let len = doc.get(key).and_then(Value::as_array).map_or(0, Vec::len);
    let mut used = vec![false; len];
    refs(doc, &mut |v: &mut Value| {
        if let Some(u) = v.as_u64().and_then(|i| used.get_mut(i as usize)) {
            *u = true;
        }
    });
    let mut new_index = vec![0usize; len];
    let mut n = 0;
    for (i, &u) in used.iter().enumerate() {
        new_index[i] = n;
        n += usize::from(u);
    }
    refs(doc, &mut |v: &mut Value| {
        if let Some(&n) = v.as_u64().and_then(|i| new_index.get(i as usize)) {
            *v = json!(n);
        }
    });
    if let Some(list) = doc.get_mut(key).and_then(Value::as_array_mut) {
        let all = std::mem::take(list);
        *list = all
            .into_iter()
            .zip(&used)
            .filter(|(_, u)| **u)
            .map(|(v, _)| v)
            .collect();
    }
}

/// `doc` and its one buffer `bin` without what nothing names; unchanged
/// where a reference might be unknown.
pub fn compact(doc: &mut Value, bin: Vec<u8>) -> Vec<u8> {
    let used = doc["extensionsUsed"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    let one_buffer = doc["buffers"].as_array().is_some_and(|b| b.len() == 1);
    if !one_buffer || !used.iter().all(|e| e.as_str().is_some_and(harmless)) {
        return bin;
    }
    // Every view inside the buffer, or the document is left whole.
    let inside = |v: &Value| {
        let start = v["byteOffset"].as_u64().unwrap_or(0) as usize;
        let length = v["byteLength"].as_u64().unwrap_or(0) as usize;
        start
            .checked_add(length)
            .is_some_and(|end| end <= bin.len())
    };
    if !doc
        .get("bufferViews")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .all(inside)
    {
        return bin;
    }
    keep_used(doc, "accessors", accessor_refs);
    keep_used(doc, "bufferViews", view_refs);
    let mut out = Vec::with_capacity(bin.len());
    for view in array(doc, "bufferViews") {
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        let length = view["byteLength"].as_u64().unwrap_or(0) as usize;
        while !out.len().is_multiple_of(4) {
            out.push(0);
        }
        view["byteOffset"] = json!(out.len());
        out.extend_from_slice(&bin[start..start + length]);
    }
    while !out.len().is_multiple_of(4) {
        out.push(0);
    }
    doc["buffers"][0]["byteLength"] = json!(out.len());
    out
}
