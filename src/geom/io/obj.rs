//! Wavefront OBJ + MTL reader.
//!
//! Reads `v`, `vt`, `vn`, `f` (polygons fan-triangulated, negative indices allowed), `usemtl`
//! and `mtllib`; MTL `newmtl`, `Kd` and `map_Kd`. Each distinct `v/vt/vn` triple becomes one
//! vertex. `vt` is flipped to the image convention (`t = 1 − v`). Errors name the line.

use super::{LoadedMesh, load_texture, malformed, read_file};
use crate::geom::{Material, Mesh, MeshError, SourceCounts, Warning};
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// Loads an OBJ file and the MTL libraries it names.
pub fn load(path: &Path) -> Result<LoadedMesh, MeshError> {
    let bytes = read_file(path)?;
    let text = String::from_utf8_lossy(&bytes);
    let mut warnings = Vec::new();

    let mut v: Vec<Vec3> = Vec::new();
    let mut vt: Vec<Vec2> = Vec::new();
    let mut vn: Vec<Vec3> = Vec::new();
    let mut materials: Vec<Material> = Vec::new();
    let mut material_index: HashMap<String, u32> = HashMap::new();
    let mut current_material = 0u32;

    // Unified vertices: (v, vt, vn) → index.
    let mut unify: HashMap<(u32, u32, u32), u32> = HashMap::new();
    let mut corners: Vec<(u32, u32, u32)> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut face_material: Vec<u32> = Vec::new();
    let mut all_have_vn = true;
    let mut any_vt = false;

    for (line_no, line) in text.lines().enumerate() {
        let element = || format!("line {}", line_no + 1);
        let line = line.split('#').next().unwrap_or("").trim();
        let mut tokens = line.split_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        match keyword {
            "v" => v.push(parse_vec3(path, &element(), &mut tokens)?),
            "vn" => vn.push(parse_vec3(path, &element(), &mut tokens)?),
            "vt" => {
                let u = parse_f32(path, &element(), tokens.next())?;
                let t = match tokens.next() {
                    Some(s) => parse_f32(path, &element(), Some(s))?,
                    None => 0.0,
                };
                vt.push(Vec2::new(u, 1.0 - t));
            }
            "f" => {
                let mut poly: Vec<u32> = Vec::with_capacity(4);
                for tok in tokens {
                    let mut parts = tok.split('/');
                    let iv =
                        resolve(path, &element(), parts.next(), v.len())?.ok_or_else(|| {
                            malformed(
                                path,
                                element(),
                                format!("face corner {tok:?} has no vertex index"),
                            )
                        })?;
                    let it = resolve(path, &element(), parts.next(), vt.len())?;
                    let inn = resolve(path, &element(), parts.next(), vn.len())?;
                    any_vt |= it.is_some();
                    all_have_vn &= inn.is_some();
                    let key = (iv, it.map_or(u32::MAX, |x| x), inn.map_or(u32::MAX, |x| x));
                    let next = corners.len() as u32;
                    let idx = *unify.entry(key).or_insert_with(|| {
                        corners.push(key);
                        next
                    });
                    poly.push(idx);
                }
                if poly.len() < 3 {
                    return Err(malformed(
                        path,
                        element(),
                        "a face needs at least 3 vertices",
                    ));
                }
                for k in 1..poly.len() - 1 {
                    triangles.push([poly[0], poly[k], poly[k + 1]]);
                    face_material.push(current_material);
                }
            }
            "usemtl" => {
                let name = tokens.collect::<Vec<_>>().join(" ");
                current_material = match material_index.get(&name) {
                    Some(&i) => i,
                    None => {
                        // Used before (or without) its definition: a grey stand-in, named.
                        materials.push(Material {
                            name: name.clone(),
                            ..Material::default()
                        });
                        let i = materials.len() as u32 - 1;
                        material_index.insert(name, i);
                        i
                    }
                };
            }
            "mtllib" => {
                let name = tokens.collect::<Vec<_>>().join(" ");
                let mtl_path = path.parent().unwrap_or(Path::new(".")).join(&name);
                match std::fs::read(&mtl_path) {
                    Ok(bytes) => load_mtl(&mtl_path, &bytes, &mut materials, &mut material_index)?,
                    Err(e) => warnings.push(Warning::Skipped {
                        path: path.to_path_buf(),
                        what: format!("material library {name:?} ({e}); using grey"),
                    }),
                }
            }
            _ => {} // o, g, s, l, p and others do not affect triangles.
        }
    }

    let positions = corners.iter().map(|c| v[c.0 as usize]).collect();
    let normals = all_have_vn.then(|| corners.iter().map(|c| vn[c.2 as usize]).collect());
    let uvs = any_vt.then(|| {
        corners
            .iter()
            .map(|c| vt.get(c.1 as usize).copied().unwrap_or(Vec2::ZERO))
            .collect()
    });
    let source = SourceCounts {
        vertices: v.len(),
        triangles: triangles.len(),
    };
    let mesh = Mesh::from_parts(
        path,
        positions,
        normals,
        uvs,
        triangles,
        face_material,
        materials,
        &mut warnings,
    )?;
    Ok(LoadedMesh {
        mesh,
        source,
        warnings,
    })
}

fn parse_f32(path: &Path, element: &str, tok: Option<&str>) -> Result<f32, MeshError> {
    let tok = tok.ok_or_else(|| malformed(path, element, "missing number"))?;
    let x: f32 = tok
        .parse()
        .map_err(|_| malformed(path, element, format!("{tok:?} is not a number")))?;
    if !x.is_finite() {
        return Err(MeshError::NonFinite {
            path: path.to_path_buf(),
            element: element.to_string(),
        });
    }
    Ok(x)
}

fn parse_vec3<'a>(
    path: &Path,
    element: &str,
    tokens: &mut impl Iterator<Item = &'a str>,
) -> Result<Vec3, MeshError> {
    Ok(Vec3::new(
        parse_f32(path, element, tokens.next())?,
        parse_f32(path, element, tokens.next())?,
        parse_f32(path, element, tokens.next())?,
    ))
}

/// Resolves a 1-based (or negative, relative) OBJ index; `None` for an empty field.
fn resolve(
    path: &Path,
    element: &str,
    field: Option<&str>,
    count: usize,
) -> Result<Option<u32>, MeshError> {
    let Some(field) = field.filter(|f| !f.is_empty()) else {
        return Ok(None);
    };
    let i: i64 = field
        .parse()
        .map_err(|_| malformed(path, element, format!("{field:?} is not an index")))?;
    let resolved = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || resolved < 0 || resolved >= count as i64 {
        return Err(MeshError::IndexOutOfRange {
            path: path.to_path_buf(),
            element: element.to_string(),
            index: i,
            count,
        });
    }
    Ok(Some(resolved as u32))
}

fn load_mtl(
    path: &Path,
    bytes: &[u8],
    materials: &mut Vec<Material>,
    index: &mut HashMap<String, u32>,
) -> Result<(), MeshError> {
    let text = String::from_utf8_lossy(bytes);
    let mut current: Option<usize> = None;
    for (line_no, line) in text.lines().enumerate() {
        let element = format!("line {}", line_no + 1);
        let line = line.split('#').next().unwrap_or("").trim();
        let mut tokens = line.split_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        match keyword {
            "newmtl" => {
                let name = tokens.collect::<Vec<_>>().join(" ");
                let i = match index.get(&name) {
                    Some(&i) => i as usize,
                    None => {
                        materials.push(Material {
                            name: name.clone(),
                            ..Material::default()
                        });
                        index.insert(name, materials.len() as u32 - 1);
                        materials.len() - 1
                    }
                };
                current = Some(i);
            }
            "Kd" => {
                let kd = parse_vec3(path, &element, &mut tokens)?;
                if let Some(m) = current.and_then(|i| materials.get_mut(i)) {
                    m.base_color = kd;
                }
            }
            "map_Kd" => {
                // Options (-s, -o …) precede the file name; the name is the last token.
                let name = tokens
                    .last()
                    .ok_or_else(|| malformed(path, &element, "map_Kd names no file"))?;
                let tex = load_texture(path, name)?;
                if let Some(m) = current.and_then(|i| materials.get_mut(i)) {
                    m.texture = Some(tex);
                }
            }
            _ => {}
        }
    }
    // MTL renderers disagree on whether Kd tints map_Kd; most (Blender, Mitsuba) show the
    // texture as is, so a textured material's colour comes from the texture alone.
    for m in materials.iter_mut().filter(|m| m.texture.is_some()) {
        m.base_color = Vec3::ONE;
    }
    Ok(())
}
