//! Wavefront OBJ + MTL reader.
//!
//! Reads `v`, `vt`, `vn`, `f` (polygons fan-triangulated, negative indices allowed), `usemtl`
//! and `mtllib`; MTL `newmtl`, `Kd` and `map_Kd`. Each distinct `v/vt/vn` triple becomes one
//! vertex. `vt` is flipped to the image convention (`t = 1 − v`). Errors name the line.

use super::{LoadedMesh, Reads, load_texture, malformed, read_file};
use crate::geom::{Material, Mesh, MeshError, SourceCounts, Warning};
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// Loads an OBJ file and the MTL libraries it names.
pub fn load(path: &Path) -> Result<LoadedMesh, MeshError> {
    let bytes = read_file(path)?;
    // A UTF-8 byte-order mark is not part of the first line.
    let text = String::from_utf8_lossy(bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&bytes));
    let mut warnings = Vec::new();
    let mut reads = Reads {
        files: vec![path.to_path_buf()],
        ..Reads::default()
    };

    let mut v: Vec<Vec3> = Vec::new();
    let mut vt: Vec<Vec2> = Vec::new();
    let mut vn: Vec<Vec3> = Vec::new();
    let mut materials: Vec<Material> = Vec::new();
    let mut material_index: HashMap<String, u32> = HashMap::new();
    let mut current_material = 0u32;
    // `usemtl` of a name no library had defined yet (line, name), and the names libraries define.
    let mut undefined: Vec<(usize, String)> = Vec::new();
    let mut defined: std::collections::HashSet<String> = std::collections::HashSet::new();

    // Unified vertices: (v, vt, vn) → index.
    let mut unify: HashMap<(u32, u32, u32), u32> = HashMap::new();
    // Unified vertices of corners with a position only: `bare[v]` (`u32::MAX` until seen).
    let mut bare: Vec<u32> = Vec::new();
    let mut corners: Vec<(u32, u32, u32)> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut face_material: Vec<u32> = Vec::new();
    let mut all_have_vn = true;
    let mut any_vt = false;

    for (line_no, line) in text.lines().enumerate() {
        let at = Line {
            path,
            number: line_no + 1,
        };
        let line = line.split('#').next().unwrap_or("").trim();
        let mut tokens = line.split_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        match keyword {
            "v" => v.push(parse_vec3(&at, &mut tokens)?),
            "vn" => vn.push(parse_vec3(&at, &mut tokens)?),
            "vt" => {
                let u = parse_f32(&at, tokens.next())?;
                let t = match tokens.next() {
                    Some(s) => parse_f32(&at, Some(s))?,
                    None => 0.0,
                };
                vt.push(Vec2::new(u, 1.0 - t));
            }
            "f" => {
                let mut poly: Vec<u32> = Vec::with_capacity(4);
                for tok in tokens {
                    let mut parts = tok.split('/');
                    let iv = resolve(&at, parts.next(), v.len(), "vertex")?.ok_or_else(|| {
                        at.malformed(format!("face corner {tok:?} has no vertex index"))
                    })?;
                    let it = resolve(&at, parts.next(), vt.len(), "texture coordinate")?;
                    let inn = resolve(&at, parts.next(), vn.len(), "normal")?;
                    any_vt |= it.is_some();
                    all_have_vn &= inn.is_some();
                    let key = (iv, it.map_or(u32::MAX, |x| x), inn.map_or(u32::MAX, |x| x));
                    let next = corners.len() as u32;
                    let slot = if it.is_none() && inn.is_none() {
                        // A bare `v` corner (scans often have nothing else): indexed directly,
                        // no hashing. `iv < v.len()`, so this grows with the file.
                        let i = iv as usize;
                        if i >= bare.len() {
                            bare.resize(v.len(), u32::MAX);
                        }
                        &mut bare[i]
                    } else {
                        unify.entry(key).or_insert(u32::MAX)
                    };
                    if *slot == u32::MAX {
                        *slot = next;
                        corners.push(key);
                    }
                    let idx = *slot;
                    poly.push(idx);
                }
                if poly.len() < 3 {
                    return Err(at.malformed("a face needs at least 3 vertices"));
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
                        undefined.push((line_no + 1, name.clone()));
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
                    Ok(bytes) => {
                        reads.files.push(mtl_path.clone());
                        load_mtl(
                            &mtl_path,
                            &bytes,
                            (&mut materials, &mut material_index, &mut defined),
                            &mut reads,
                            &mut warnings,
                        )?
                    }
                    Err(e) => warnings.push(Warning::Skipped {
                        path: path.to_path_buf(),
                        what: format!("material library {name:?} ({e}); using grey"),
                    }),
                }
            }
            _ => {} // o, g, s, l, p and others do not affect triangles.
        }
    }
    for (line, name) in undefined.iter().filter(|(_, n)| !defined.contains(n)) {
        warnings.push(Warning::Skipped {
            path: path.to_path_buf(),
            what: format!("line {line}: usemtl {name:?} names no material a library defines; grey"),
        });
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
        files: reads.files,
    })
}

/// Where in an OBJ file a value is read: errors name the line, formatted only when one occurs
/// (formatting it for every value read took a quarter of a large file's load).
struct Line<'a> {
    path: &'a Path,
    number: usize,
}

impl Line<'_> {
    fn element(&self) -> String {
        format!("line {}", self.number)
    }

    fn malformed(&self, reason: impl Into<String>) -> MeshError {
        malformed(self.path, self.element(), reason)
    }
}

fn parse_f32(at: &Line<'_>, tok: Option<&str>) -> Result<f32, MeshError> {
    let tok = tok.ok_or_else(|| at.malformed("missing number"))?;
    let x: f32 = tok
        .parse()
        .map_err(|_| at.malformed(format!("{tok:?} is not a number")))?;
    if !x.is_finite() {
        return Err(MeshError::NonFinite {
            path: at.path.to_path_buf(),
            element: at.element(),
        });
    }
    Ok(x)
}

fn parse_vec3<'a>(
    at: &Line<'_>,
    tokens: &mut impl Iterator<Item = &'a str>,
) -> Result<Vec3, MeshError> {
    Ok(Vec3::new(
        parse_f32(at, tokens.next())?,
        parse_f32(at, tokens.next())?,
        parse_f32(at, tokens.next())?,
    ))
}

/// Resolves a 1-based (or negative, relative) OBJ index; `None` for an empty field.
/// Resolves one index of a face corner against the `count` elements of its `kind` (`v`, `vt`
/// or `vn`) read so far; an index out of range names what it counts.
fn resolve(
    at: &Line<'_>,
    field: Option<&str>,
    count: usize,
    kind: &'static str,
) -> Result<Option<u32>, MeshError> {
    let Some(field) = field.filter(|f| !f.is_empty()) else {
        return Ok(None);
    };
    let i: i64 = field
        .parse()
        .map_err(|_| at.malformed(format!("{field:?} is not an index")))?;
    let resolved = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || resolved < 0 || resolved >= count as i64 {
        return Err(MeshError::IndexOutOfRange {
            path: at.path.to_path_buf(),
            element: at.element(),
            kind,
            index: i,
            count,
        });
    }
    Ok(Some(resolved as u32))
}

/// MTL statements trompe reads past: understood, but not part of its materials.
const MTL_UNUSED: [&str; 27] = [
    "ka",
    "ks",
    "ke",
    "ns",
    "ni",
    "d",
    "tr",
    "tf",
    "illum",
    "sharpness",
    "map_ka",
    "map_ks",
    "map_ke",
    "map_ns",
    "map_d",
    "map_bump",
    "bump",
    "disp",
    "decal",
    "refl",
    "norm",
    "pc",
    "pcr",
    "ps",
    "aniso",
    "anisor",
    "map_pr",
];

/// The most statements an MTL file warns of one by one; the rest are counted.
const MTL_WARNINGS: usize = 10;

fn load_mtl(
    path: &Path,
    bytes: &[u8],
    (materials, index, defined): (
        &mut Vec<Material>,
        &mut HashMap<String, u32>,
        &mut std::collections::HashSet<String>,
    ),
    reads: &mut Reads,
    warnings: &mut Vec<Warning>,
) -> Result<(), MeshError> {
    let text = String::from_utf8_lossy(bytes);
    let mut current: Option<usize> = None;
    let mut not_understood: Vec<(usize, String)> = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let at = Line {
            path,
            number: line_no + 1,
        };
        let line = line.split('#').next().unwrap_or("").trim();
        let mut tokens = line.split_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        // Keywords as written by any exporter's capitalisation (`map_kd`, `KD`).
        let lower = keyword.to_ascii_lowercase();
        if current.is_none() && lower != "newmtl" && !MTL_UNUSED.contains(&lower.as_str()) {
            not_understood.push((line_no + 1, format!("{line} (before any newmtl)")));
            continue;
        }
        let keyword = match lower.as_str() {
            "kd" => "Kd",
            "pr" => "Pr",
            "pm" => "Pm",
            "map_kd" => "map_Kd",
            "newmtl" => "newmtl",
            k if MTL_UNUSED.contains(&k) => continue,
            _ => {
                not_understood.push((line_no + 1, line.to_string()));
                continue;
            }
        };
        match keyword {
            "newmtl" => {
                let name = tokens.collect::<Vec<_>>().join(" ");
                defined.insert(name.clone());
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
                let kd = parse_vec3(&at, &mut tokens)?;
                if let Some(m) = current.and_then(|i| materials.get_mut(i)) {
                    m.base_color = kd;
                }
            }
            // The PBR extension of MTL (Blender and others write it).
            "Pr" | "Pm" => {
                let v = tokens
                    .next()
                    .and_then(|t| t.parse::<f32>().ok())
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| at.malformed(format!("{keyword} needs a number")))?;
                if let Some(m) = current.and_then(|i| materials.get_mut(i)) {
                    match keyword {
                        "Pr" => m.roughness = v.clamp(0.0, 1.0),
                        _ => m.metallic = v.clamp(0.0, 1.0),
                    }
                }
            }
            "map_Kd" => {
                // Options (-s, -o …) precede the file name; the name is the last token.
                let name = tokens
                    .last()
                    .ok_or_else(|| at.malformed("map_Kd names no file"))?;
                let tex = load_texture(path, name, reads)?;
                if let Some(m) = current.and_then(|i| materials.get_mut(i)) {
                    m.texture = Some(tex);
                }
            }
            _ => {}
        }
    }
    for (line, statement) in not_understood.iter().take(MTL_WARNINGS) {
        warnings.push(Warning::Skipped {
            path: path.to_path_buf(),
            what: format!("line {line}: {statement:?} is not an MTL statement trompe knows"),
        });
    }
    if not_understood.len() > MTL_WARNINGS {
        warnings.push(Warning::Skipped {
            path: path.to_path_buf(),
            what: format!(
                "{} more statements trompe does not know",
                not_understood.len() - MTL_WARNINGS
            ),
        });
    }
    // MTL renderers disagree on whether Kd tints map_Kd; most (Blender, Mitsuba) show the
    // texture as is, so a textured material's colour comes from the texture alone.
    for m in materials.iter_mut().filter(|m| m.texture.is_some()) {
        m.base_color = Vec3::ONE;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Statements an MTL reader does not know, a texture before any `newmtl` and an undefined
    /// material are warnings naming the line; capitalisation does not lose a texture.
    #[test]
    fn mtl_statements_not_understood_are_warnings_naming_the_line() {
        let dir = crate::test_scratch::scratch("obj-mtl-warnings");
        image::RgbImage::new(2, 2).save(dir.join("t.png")).unwrap();
        std::fs::write(
            dir.join("m.mtl"),
            "map_Kd t.png\nnewmtl a\nKs 1 1 1\nMAP_KD t.png\nmap_Kdd t.png\n",
        )
        .unwrap();
        let path = dir.join("m.obj");
        std::fs::write(
            &path,
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 2 3\n",
        )
        .unwrap();
        let loaded = load(&path).unwrap();
        let text: Vec<String> = loaded.warnings.iter().map(|w| w.to_string()).collect();
        assert_eq!(text.len(), 3, "{text:?}");
        assert!(
            text[0].contains("line 1") && text[0].contains("before any newmtl"),
            "{text:?}"
        );
        assert!(
            text[1].contains("line 5") && text[1].contains("map_Kdd"),
            "{text:?}"
        );
        assert!(
            text[2].contains("line 7") && text[2].contains("usemtl \"b\""),
            "{text:?}"
        );
        assert!(
            loaded.mesh.materials[0].texture.is_some(),
            "MAP_KD is map_Kd"
        );
    }

    fn load_text(name: &str, text: &str) -> Result<LoadedMesh, MeshError> {
        let dir = crate::test_scratch::scratch(&format!("obj-{name}"));
        let path = dir.join(name);
        std::fs::write(&path, text).expect("write");
        load(&path)
    }

    /// A corner with a position only and one with a texture coordinate are different vertices,
    /// even at the same position; a repeated corner of either kind is one vertex.
    #[test]
    fn corners_unify_by_position_texture_and_normal_together() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5 0.5\n\
                    f 1 2 3\nf 1 3 2\nf 1/1 2/1 3/1\nf 3/1 2/1 1/1\n";
        let m = load_text("mixed.obj", text).expect("valid").mesh;
        assert_eq!(m.positions.len(), 6);
        assert_eq!(
            m.triangles,
            vec![[0, 1, 2], [0, 2, 1], [3, 4, 5], [5, 4, 3]]
        );
    }

    /// Errors name the line they come from (formatted only when one occurs).
    #[test]
    fn a_bad_value_is_reported_with_its_line() {
        let e = load_text("bad_value.obj", "v 0 0 0\nv 1 0 0\nv 0 x 0\nf 1 2 3\n")
            .expect_err("a bad number");
        assert!(e.to_string().contains("line 3"), "{e}");
        let e = load_text("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 9\n")
            .expect_err("an index out of range");
        assert!(e.to_string().contains("line 5"), "{e}");
    }
}
