//! glTF 2.0 reader (`.gltf` with external or embedded buffers, and `.glb`), via the `gltf` crate.
//!
//! The default scene's node hierarchy is flattened: every triangle primitive of every mesh
//! instance is transformed by its node's world matrix and appended, so an instanced mesh counts
//! once per instance. Base-colour factor and texture (`TEXCOORD_0`), normals and UVs are read.
//! Missing buffers or images and out-of-range accessors are errors naming the element, checked
//! before the crate's readers slice any buffer.

use super::{LoadedMesh, malformed, read_file};
use crate::geom::{Material, Mesh, MeshError, SourceCounts, Warning};
use glam::{Mat4, Vec2, Vec3};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// Loads a `.gltf` or `.glb` file.
pub fn load(path: &Path) -> Result<LoadedMesh, MeshError> {
    let bytes = read_file(path)?;
    // Compressed geometry (quantized, meshopt) becomes plain glTF first: the crate refuses it.
    let bytes = super::compressed::decode_glb(path, &bytes)?.unwrap_or(bytes);
    check_references(path, &bytes)?;
    // The last line of defence: a decoder panic on a file no check above foresaw becomes an
    // error naming the file, not an abort.
    let parsed = std::panic::catch_unwind(|| gltf::Gltf::from_slice(&bytes)).map_err(|_| {
        malformed(
            path,
            "document",
            "the glTF decoder failed on this file (malformed)",
        )
    })?;
    let gltf = parsed.map_err(|e| malformed(path, "document", e.to_string()))?;
    validate(path, gltf.document.as_json())?;
    let base = path.parent().unwrap_or(Path::new("."));
    let mut files = vec![path.to_path_buf()];
    files.extend(check_external_files(path, base, &gltf.document)?);
    let buffers = gltf::import_buffers(&gltf.document, Some(base), gltf.blob.clone())
        .map_err(|e| malformed(path, "buffers", e.to_string()))?;
    for view in gltf.document.views() {
        let len = buffers.get(view.buffer().index()).map_or(0, |b| b.len());
        if view.offset().saturating_add(view.length()) > len {
            return Err(malformed(
                path,
                format!("bufferView {}", view.index()),
                format!(
                    "bytes {}..{} past the end of buffer {} ({len} bytes)",
                    view.offset(),
                    view.offset() + view.length(),
                    view.buffer().index()
                ),
            ));
        }
    }

    let mut warnings = Vec::new();
    let mut state = Flatten {
        path,
        buffers: &buffers,
        document: &gltf.document,
        base,
        textures: HashMap::new(),
        materials: HashMap::new(),
        mesh: Mesh::default(),
        normals_present: true,
        source: SourceCounts::default(),
        warnings: &mut warnings,
    };
    let scene = gltf
        .document
        .default_scene()
        .or_else(|| gltf.document.scenes().next())
        .ok_or_else(|| malformed(path, "document", "no scene"))?;
    check_instances(path, &scene)?;
    for node in scene.nodes() {
        state.visit(&node, Mat4::IDENTITY, 0)?;
    }
    let Flatten {
        mesh: flat,
        normals_present,
        source,
        ..
    } = state;
    let mesh = Mesh::from_parts(
        path,
        flat.positions,
        normals_present.then_some(flat.normals),
        flat.uvs,
        flat.triangles,
        flat.face_material,
        flat.materials,
        &mut warnings,
    )?;
    Ok(LoadedMesh {
        mesh,
        source,
        warnings,
        files,
    })
}

/// Every index the document's meshes, nodes, scenes, accessors and textures hold is in range —
/// checked on the raw JSON (of a `.gltf`, or a `.glb`'s JSON chunk), because the `gltf` crate's
/// own validation indexes some of them unchecked.
fn check_references(path: &Path, bytes: &[u8]) -> Result<(), MeshError> {
    use serde_json::Value;
    let json: std::borrow::Cow<[u8]> = if bytes.starts_with(b"glTF") {
        match gltf::Glb::from_slice(bytes) {
            Ok(glb) => glb.json,
            Err(e) => return Err(malformed(path, "GLB container", e.to_string())),
        }
    } else {
        std::borrow::Cow::Borrowed(bytes)
    };
    // The decoder skips the keys it does not know without checking that they are UTF-8, so a
    // document with a broken key still decodes: read it the same way here (broken bytes
    // replaced), or its indices would go unchecked.
    let root = serde_json::from_slice::<Value>(&json)
        .or_else(|_| serde_json::from_str::<Value>(&String::from_utf8_lossy(&json)));
    let Ok(root) = root else {
        return Ok(()); // Not JSON: the decoder says why.
    };
    let count = |key: &str| root.get(key).and_then(Value::as_array).map_or(0, Vec::len);
    let array = |v: &Value, key: &str| -> Vec<Value> {
        v.get(key)
            .and_then(Value::as_array)
            .cloned()
            .unwrap_or_default()
    };
    let check = |element: String, what: &str, v: Option<&Value>, n: usize| match v {
        None => Ok(()),
        Some(i) => match i.as_u64() {
            Some(i) if (i as usize) < n => Ok(()),
            _ => Err(malformed(
                path,
                element,
                format!("{what} {i} does not exist ({n} in the file)"),
            )),
        },
    };
    let (accessors, views, meshes, nodes) = (
        count("accessors"),
        count("bufferViews"),
        count("meshes"),
        count("nodes"),
    );
    for (m, mesh) in array(&root, "meshes").iter().enumerate() {
        for (p, prim) in array(mesh, "primitives").iter().enumerate() {
            let at = format!("mesh {m} primitive {p}");
            check(at.clone(), "accessor", prim.get("indices"), accessors)?;
            check(
                at.clone(),
                "material",
                prim.get("material"),
                count("materials"),
            )?;
            if let Some(attrs) = prim.get("attributes").and_then(Value::as_object) {
                for (name, a) in attrs {
                    check(format!("{at} {name}"), "accessor", Some(a), accessors)?;
                }
            }
        }
    }
    for (a, acc) in array(&root, "accessors").iter().enumerate() {
        check(
            format!("accessor {a}"),
            "bufferView",
            acc.get("bufferView"),
            views,
        )?;
    }
    for (n, node) in array(&root, "nodes").iter().enumerate() {
        check(format!("node {n}"), "mesh", node.get("mesh"), meshes)?;
        for c in array(node, "children") {
            check(format!("node {n}"), "node", Some(&c), nodes)?;
        }
    }
    for (s, scene) in array(&root, "scenes").iter().enumerate() {
        for c in array(scene, "nodes") {
            check(format!("scene {s}"), "node", Some(&c), nodes)?;
        }
    }
    check(
        "document".into(),
        "scene",
        root.get("scene"),
        count("scenes"),
    )?;
    for (t, tex) in array(&root, "textures").iter().enumerate() {
        check(
            format!("texture {t}"),
            "image",
            tex.get("source"),
            count("images"),
        )?;
    }
    Ok(())
}

/// The rules of the glTF 2.0 specification that the `gltf` crate's readers assume rather than
/// check (they panic on a file that breaks them), checked on the document before any data is
/// read: every index in range, index and attribute accessors of the component types and shapes
/// the specification allows, strides no smaller than an element, images with a source.
fn validate(path: &Path, root: &gltf::json::Root) -> Result<(), MeshError> {
    use gltf::json::accessor::{ComponentType, Type};
    use gltf::json::validation::Checked;
    let (n_acc, n_views, n_buffers) = (
        root.accessors.len(),
        root.buffer_views.len(),
        root.buffers.len(),
    );
    let bad = |element: String, reason: String| malformed(path, element, reason);
    let in_range = |what: &str, i: usize, n: usize, element: String| {
        if i < n {
            Ok(())
        } else {
            Err(bad(
                element,
                format!("{what} {i} does not exist ({n} in the file)"),
            ))
        }
    };
    for (v, view) in root.buffer_views.iter().enumerate() {
        in_range(
            "buffer",
            view.buffer.value(),
            n_buffers,
            format!("bufferView {v}"),
        )?;
    }
    for (a, acc) in root.accessors.iter().enumerate() {
        if let Some(view) = acc.buffer_view {
            in_range("bufferView", view.value(), n_views, format!("accessor {a}"))?;
            let (Checked::Valid(ct), Checked::Valid(ty)) = (&acc.component_type, &acc.type_) else {
                return Err(bad(
                    format!("accessor {a}"),
                    "unknown component type or type".into(),
                ));
            };
            let element = ct.0.size() * ty.multiplicity();
            if let Some(stride) = root.buffer_views[view.value()].byte_stride
                && stride.0 < element
            {
                return Err(bad(
                    format!("accessor {a}"),
                    format!(
                        "byteStride {} of bufferView {} is smaller than one element ({element} bytes)",
                        stride.0,
                        view.value()
                    ),
                ));
            }
        }
    }
    let accessor = |a: usize, element: String| -> Result<(ComponentType, Type, bool), MeshError> {
        in_range("accessor", a, n_acc, element.clone())?;
        let acc = &root.accessors[a];
        match (&acc.component_type, &acc.type_) {
            (Checked::Valid(ct), Checked::Valid(ty)) => Ok((ct.0, *ty, acc.normalized)),
            _ => Err(bad(element, "unknown component type or type".into())),
        }
    };
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let at = |what: &str| format!("mesh {m} primitive {p} {what}");
            if let Some(i) = prim.indices {
                let (ct, ty, _) = accessor(i.value(), at("indices"))?;
                let unsigned = matches!(
                    ct,
                    ComponentType::U8 | ComponentType::U16 | ComponentType::U32
                );
                if !unsigned || ty != Type::Scalar {
                    return Err(bad(
                        at("indices"),
                        format!(
                            "accessor {} is {ct:?} {ty:?}; indices are unsigned byte, short or int scalars",
                            i.value()
                        ),
                    ));
                }
            }
            for (semantic, a) in &prim.attributes {
                let Checked::Valid(semantic) = semantic else {
                    continue;
                };
                let (ct, ty, normalized) = accessor(a.value(), at(&format!("{semantic:?}")))?;
                use gltf::json::mesh::Semantic;
                let allowed = match semantic {
                    Semantic::Positions | Semantic::Normals => {
                        ct == ComponentType::F32 && ty == Type::Vec3
                    }
                    Semantic::TexCoords(_) => {
                        ty == Type::Vec2
                            && (ct == ComponentType::F32
                                || (normalized
                                    && matches!(ct, ComponentType::U8 | ComponentType::U16)))
                    }
                    _ => true,
                };
                if !allowed {
                    return Err(bad(
                        at(&format!("{semantic:?}")),
                        format!(
                            "accessor {} is {ct:?} {ty:?}{}, which the specification does not allow for it",
                            a.value(),
                            if normalized { " normalized" } else { "" }
                        ),
                    ));
                }
            }
            if let Some(mat) = prim.material {
                in_range(
                    "material",
                    mat.value(),
                    root.materials.len(),
                    at("material"),
                )?;
            }
        }
    }
    for (n, node) in root.nodes.iter().enumerate() {
        if let Some(mesh) = node.mesh {
            in_range("mesh", mesh.value(), root.meshes.len(), format!("node {n}"))?;
        }
        for c in node.children.iter().flatten() {
            in_range("node", c.value(), root.nodes.len(), format!("node {n}"))?;
        }
    }
    for (s, scene) in root.scenes.iter().enumerate() {
        for c in &scene.nodes {
            in_range("node", c.value(), root.nodes.len(), format!("scene {s}"))?;
        }
    }
    for (t, tex) in root.textures.iter().enumerate() {
        in_range(
            "image",
            tex.source.value(),
            root.images.len(),
            format!("texture {t}"),
        )?;
    }
    for (m, mat) in root.materials.iter().enumerate() {
        if let Some(info) = &mat.pbr_metallic_roughness.base_color_texture {
            in_range(
                "texture",
                info.index.value(),
                root.textures.len(),
                format!("material {m}"),
            )?;
        }
    }
    for (i, image) in root.images.iter().enumerate() {
        match (&image.uri, &image.buffer_view, &image.mime_type) {
            (Some(_), None, _) => {}
            (None, Some(view), Some(_)) => {
                in_range("bufferView", view.value(), n_views, format!("image {i}"))?;
            }
            (None, Some(_), None) => {
                return Err(bad(
                    format!("image {i}"),
                    "a bufferView image needs a mimeType".into(),
                ));
            }
            _ => {
                return Err(bad(
                    format!("image {i}"),
                    "needs either a uri or a bufferView".into(),
                ));
            }
        }
    }
    Ok(())
}

/// Why the file `uri` names beside the document is not a file one can read.
fn missing_file(base: &Path, uri: &str) -> String {
    if base.join(uri).is_dir() {
        format!("{uri:?} is a folder, not a file")
    } else {
        format!("file {uri:?} not found")
    }
}

/// The external files `doc` names (buffers, images), each checked to exist.
fn check_external_files(
    path: &Path,
    base: &Path,
    doc: &gltf::Document,
) -> Result<Vec<std::path::PathBuf>, MeshError> {
    let mut files = Vec::new();
    for b in doc.buffers() {
        if let gltf::buffer::Source::Uri(uri) = b.source() {
            if !uri.starts_with("data:") {
                files.push(base.join(uri));
            }
            if !uri.starts_with("data:") && !base.join(uri).is_file() {
                return Err(malformed(
                    path,
                    format!("buffer {}", b.index()),
                    missing_file(base, uri),
                ));
            }
        }
    }
    for i in doc.images() {
        if let gltf::image::Source::Uri { uri, .. } = i.source() {
            if !uri.starts_with("data:") {
                files.push(base.join(uri));
            }
            if !uri.starts_with("data:") && !base.join(uri).is_file() {
                return Err(malformed(
                    path,
                    format!("image {}", i.index()),
                    missing_file(base, uri),
                ));
            }
        }
    }
    Ok(files)
}

/// The accessors that define a primitive's vertices: POSITION, NORMAL, TEXCOORD_0.
type VertexKey = (Option<usize>, Option<usize>, Option<usize>);

fn vertex_key(prim: &gltf::Primitive) -> VertexKey {
    use gltf::Semantic;
    let index = |s: Semantic| prim.get(&s).map(|a| a.index());
    (
        index(Semantic::Positions),
        index(Semantic::Normals),
        index(Semantic::TexCoords(0)),
    )
}

/// A URI's `%XX` escapes decoded (glTF file URIs are URI-encoded).
fn percent_decoded(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        match (
            b[i],
            b.get(i + 1).copied().and_then(hex),
            b.get(i + 2).copied().and_then(hex),
        ) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (c, _, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Bytes a vertex of the flattened mesh costs (position, normal, texture coordinate and the
/// loader's bookkeeping), and a triangle (indices and material).
const BYTES_PER_VERTEX: u64 = 48;
const BYTES_PER_TRIANGLE: u64 = 32;

/// Refuses a scene whose node hierarchy instances more geometry than the memory budget holds —
/// a small file can instance a mesh 2⁴⁰ times through a DAG of nodes — before any is flattened.
/// Each node's cost is counted once (memoised), so the check is linear in the document.
fn check_instances(path: &Path, scene: &gltf::Scene) -> Result<(), MeshError> {
    use crate::memory::times;
    // A count past what its bufferView holds is reported, naming the accessor, by the walk.
    fn held(accessor: &gltf::Accessor) -> u64 {
        let most = accessor.view().map_or(0, |v| {
            v.length() / v.stride().unwrap_or(accessor.size()).max(1)
        });
        accessor.count().min(most) as u64
    }
    fn mesh_bytes(mesh: &gltf::Mesh) -> u64 {
        mesh.primitives()
            .map(|p| {
                let vertices = p.get(&gltf::Semantic::Positions).map_or(0, |a| held(&a));
                let corners = p.indices().map_or(vertices, |a| held(&a));
                times(vertices, BYTES_PER_VERTEX)
                    .saturating_add(times(corners / 3, BYTES_PER_TRIANGLE))
            })
            .fold(0u64, u64::saturating_add)
    }
    fn node_bytes(node: &gltf::Node, depth: usize, memo: &mut HashMap<usize, u64>) -> Option<u64> {
        if depth > MAX_NODE_DEPTH {
            return None;
        }
        if let Some(&bytes) = memo.get(&node.index()) {
            return Some(bytes);
        }
        let mut bytes = node.mesh().map_or(0, |m| mesh_bytes(&m));
        for child in node.children() {
            bytes = bytes.saturating_add(node_bytes(&child, depth + 1, memo)?);
        }
        memo.insert(node.index(), bytes);
        Some(bytes)
    }
    let mut memo = HashMap::new();
    let mut total = 0u64;
    for node in scene.nodes() {
        // A hierarchy too deep is reported, naming the node, by the walk that flattens it.
        let Some(bytes) = node_bytes(&node, 0, &mut memo) else {
            return Ok(());
        };
        total = total.saturating_add(bytes);
    }
    crate::memory::check(|| "the scene's instanced meshes".to_string(), total).map_err(|source| {
        MeshError::Memory {
            path: path.to_path_buf(),
            source,
        }
    })
}

/// Node hierarchies deeper than this are refused (cycles are invalid glTF but must not hang).
const MAX_NODE_DEPTH: usize = 256;

struct Flatten<'a> {
    path: &'a Path,
    buffers: &'a [gltf::buffer::Data],
    /// Images are decoded only when a used material asks for one, each once, its size checked
    /// before its pixels are allocated.
    document: &'a gltf::Document,
    base: &'a Path,
    /// Decoded images by index and whether they hold colour (sRGB) or data (linear).
    textures: HashMap<(usize, bool), crate::geom::Texture>,
    materials: HashMap<Option<usize>, u32>,
    mesh: Mesh,
    normals_present: bool,
    source: SourceCounts,
    warnings: &'a mut Vec<Warning>,
}

impl Flatten<'_> {
    fn visit(&mut self, node: &gltf::Node, parent: Mat4, depth: usize) -> Result<(), MeshError> {
        if depth > MAX_NODE_DEPTH {
            return Err(malformed(
                self.path,
                format!("node {}", node.index()),
                "hierarchy too deep (a cycle?)",
            ));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if !world.is_finite() {
            return Err(MeshError::NonFinite {
                path: self.path.to_path_buf(),
                element: format!("node {} transform", node.index()),
            });
        }
        if let Some(mesh) = node.mesh() {
            // Primitives of one instance that share vertex accessors share vertices.
            let mut shared = HashMap::new();
            for prim in mesh.primitives() {
                self.primitive(&mesh, &prim, &world, &mut shared)?;
            }
        }
        for child in node.children() {
            self.visit(&child, world, depth + 1)?;
        }
        Ok(())
    }

    fn check(&self, accessor: &gltf::Accessor, what: &str) -> Result<(), MeshError> {
        let element = format!("accessor {} ({what})", accessor.index());
        let Some(view) = accessor.view() else {
            return Err(malformed(
                self.path,
                element,
                "sparse or view-less accessors are not supported",
            ));
        };
        let elem = accessor.size();
        let stride = view.stride().unwrap_or(elem);
        let need = match accessor.count() {
            0 => Some(0),
            n => (n - 1)
                .checked_mul(stride)
                .and_then(|b| b.checked_add(accessor.offset()))
                .and_then(|b| b.checked_add(elem)),
        };
        if need.is_none_or(|need| need > view.length()) {
            let need = need.map_or("more than 2⁶⁴".to_string(), |n| n.to_string());
            return Err(malformed(
                self.path,
                element,
                format!(
                    "{} items need {need} bytes but bufferView {} holds {}",
                    accessor.count(),
                    view.index(),
                    view.length()
                ),
            ));
        }
        Ok(())
    }

    fn primitive(
        &mut self,
        mesh: &gltf::Mesh,
        prim: &gltf::Primitive,
        world: &Mat4,
        shared: &mut HashMap<VertexKey, u32>,
    ) -> Result<(), MeshError> {
        if prim.mode() != gltf::mesh::Mode::Triangles {
            self.warnings.push(Warning::Skipped {
                path: self.path.to_path_buf(),
                what: format!(
                    "mesh {} primitive {}: mode {:?} is not triangles",
                    mesh.index(),
                    prim.index(),
                    prim.mode()
                ),
            });
            return Ok(());
        }
        for (sem, acc) in prim.attributes() {
            self.check(&acc, &format!("{sem:?}"))?;
        }
        if let Some(acc) = prim.indices() {
            self.check(&acc, "indices")?;
        }
        let buffers = self.buffers;
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d[..]));
        let element = || format!("mesh {} primitive {}", mesh.index(), prim.index());
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| malformed(self.path, element(), "no POSITION attribute"))?
            .map(|p| world.transform_point3(Vec3::from(p)))
            .collect();
        let n = positions.len();
        let normal_m = glam::Mat3::from_mat4(*world).inverse().transpose();
        let normals: Option<Vec<Vec3>> = reader.read_normals().map(|it| {
            it.map(|v| (normal_m * Vec3::from(v)).normalize_or_zero())
                .collect()
        });
        let uvs: Option<Vec<Vec2>> = reader
            .read_tex_coords(0)
            .map(|t| t.into_f32().map(Vec2::from).collect());
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..n as u32).collect(),
        };
        if !indices.len().is_multiple_of(3) {
            return Err(malformed(
                self.path,
                element(),
                format!("{} indices is not a multiple of 3", indices.len()),
            ));
        }
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(MeshError::IndexOutOfRange {
                path: self.path.to_path_buf(),
                kind: "vertex",
                element: element(),
                index: bad as i64,
                count: n,
            });
        }
        let material = self.material(&prim.material())?;
        let flip = world.determinant() < 0.0;
        let oriented = |t: &[u32], base: u32| {
            if flip {
                [t[0] + base, t[2] + base, t[1] + base]
            } else {
                [t[0] + base, t[1] + base, t[2] + base]
            }
        };
        self.source.triangles += indices.len() / 3;
        let key = vertex_key(prim);
        if let Some(&base) = shared.get(&key) {
            for t in indices.chunks_exact(3) {
                self.mesh.triangles.push(oriented(t, base));
                self.mesh.face_material.push(material);
            }
            return Ok(());
        }
        shared.insert(key, self.mesh.positions.len() as u32);
        self.normals_present &= normals.as_ref().is_some_and(|v| v.len() == n);
        self.source.vertices += n;
        let part = Mesh {
            normals: normals
                .filter(|v| v.len() == n)
                .unwrap_or_else(|| vec![Vec3::ZERO; n]),
            uvs: uvs.filter(|v| v.len() == n),
            triangles: indices.chunks_exact(3).map(|t| oriented(t, 0)).collect(),
            face_material: vec![0; indices.len() / 3],
            materials: Vec::new(),
            positions,
        };
        // Append with the material index resolved into the shared table.
        let first_face = self.mesh.face_material.len();
        self.mesh.append(&part);
        for m in &mut self.mesh.face_material[first_face..] {
            *m = material;
        }
        Ok(())
    }

    fn material(&mut self, m: &gltf::Material) -> Result<u32, MeshError> {
        if let Some(&i) = self.materials.get(&m.index()) {
            return Ok(i);
        }
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, _] = pbr.base_color_factor();
        let texture = match pbr.base_color_texture() {
            Some(info) => Some(self.texture(info.texture().source().index(), true)?),
            None => None,
        };
        let metallic_roughness = match pbr.metallic_roughness_texture() {
            Some(info) => Some(self.texture(info.texture().source().index(), false)?),
            None => None,
        };
        self.mesh.materials.push(Material {
            name: m.name().unwrap_or("default").to_string(),
            base_color: Vec3::new(r, g, b),
            texture,
            metallic: pbr.metallic_factor().clamp(0.0, 1.0),
            roughness: pbr.roughness_factor().clamp(0.0, 1.0),
            metallic_roughness,
        });
        let i = self.mesh.materials.len() as u32 - 1;
        self.materials.insert(m.index(), i);
        Ok(i)
    }

    /// Image `image`, decoded as colour (sRGB to linear) or as data.
    fn texture(&mut self, image: usize, color: bool) -> Result<crate::geom::Texture, MeshError> {
        if let Some(t) = self.textures.get(&(image, color)) {
            return Ok(t.clone());
        }
        let element = format!("image {image}");
        let source = self
            .document
            .images()
            .nth(image)
            .ok_or_else(|| malformed(self.path, &element, "missing"))?
            .source();
        let bytes: Vec<u8> = match source {
            gltf::image::Source::View { view, .. } => {
                let data = self.buffers.get(view.buffer().index()).map(|d| &d[..]);
                data.and_then(|d| d.get(view.offset()..view.offset() + view.length()))
                    .ok_or_else(|| {
                        malformed(self.path, &element, "its bufferView is out of range")
                    })?
                    .to_vec()
            }
            gltf::image::Source::Uri { uri, .. } => match uri.strip_prefix("data:") {
                Some(rest) => {
                    let (_, payload) = rest.split_once(";base64,").ok_or_else(|| {
                        malformed(self.path, &element, "a data URI that is not base64")
                    })?;
                    base64::decode(payload)
                        .map_err(|e| malformed(self.path, &element, e.to_string()))?
                }
                None => read_file(&self.base.join(percent_decoded(uri)))?,
            },
        };
        let decode = if color {
            crate::frame::io::decode_srgb_image
        } else {
            crate::frame::io::decode_linear_image
        };
        let texture_error = |source| MeshError::Texture {
            path: self.path.to_path_buf(),
            texture: element.clone(),
            source,
        };
        let size = crate::frame::io::image_size_of(&bytes, self.path).map_err(texture_error)?;
        super::budget_texture(|| element.clone(), size).map_err(|e| texture_error(e.into()))?;
        let img = decode(&bytes, self.path).map_err(texture_error)?;
        let t = Arc::new(img);
        self.textures.insert((image, color), t.clone());
        Ok(t)
    }
}
