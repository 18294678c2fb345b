//! The resolve: each band of the visibility buffer (triangle and barycentrics per texel) turned
//! into the impostor's maps — colour, normals, object, and for a SPOC the `gd` moved onto the
//! stored triangle's plane — once per covered texel, while the band is in cache.

use super::*;
/// The first pass of construction writes, per fragment that passes the depth test, only its
/// barycentrics (the item buffer holds its triangle): a visibility buffer. Surface attributes
/// are resolved afterwards, once per covered texel ([`resolve_run`]); writing them per
/// fragment into a wide attribute image cost more than the rasterization itself. Two weights
/// are stored, the third is `1 − b₁ − b₂` ([`full_barycentrics`]).
pub(in crate::impostor) struct Barycentrics;

impl FragmentShader for Barycentrics {
    type Output = Vec2;
    fn shade(&self, f: &Fragment) -> Vec2 {
        Vec2::new(f.bary.y, f.bary.z)
    }
}

/// The three weights from the two a [`Barycentrics`] buffer stores.
pub(in crate::impostor) fn full_barycentrics(b: Vec2) -> Vec3 {
    Vec3::new(1.0 - b.x - b.y, b.x, b.y)
}

/// A visible point of the source mesh: its triangle and barycentrics, and through a graph
/// camera the frustum that drew it — the view its face normal is turned toward. (Finding a
/// frustum again with `locate` cost 5 % of a graph build, and where frusta meet it may name
/// another one than the frustum that imaged the point: 303 texels of the demo maze at 512².)
#[derive(Clone, Copy, Debug, PartialEq)]
pub(in crate::impostor) struct Visible {
    pub(in crate::impostor) triangle: u32,
    pub(in crate::impostor) bary: Vec3,
    pub(in crate::impostor) frustum: Option<u32>,
}

/// A run of texels of every map of an impostor (the same texels of each), row-major.
pub(super) struct TexelMaps<'a> {
    pub(super) color: &'a mut [HalfRgba],
    pub(super) normal: &'a mut [OctUnit],
    pub(super) face_normal: &'a mut [OctUnit],
    /// Through a graph camera only ([`Impostor::position_at`]).
    pub(super) position: Option<&'a mut [Vec3]>,
    pub(super) object: &'a mut [u32],
}

impl Impostor {
    /// Its `gd`, and its other maps cut into runs of `n` texels (the last may be shorter) for
    /// parallel filling.
    pub(super) fn gd_and_texel_runs(&mut self, n: usize) -> (&mut Image<f32>, Vec<TexelMaps<'_>>) {
        let mut positions = self.position.as_mut().map(|p| p.pixels_mut().chunks_mut(n));
        let runs = self
            .color
            .pixels_mut()
            .chunks_mut(n)
            .zip(self.normal.pixels_mut().chunks_mut(n))
            .zip(self.face_normal.pixels_mut().chunks_mut(n))
            .zip(self.object.pixels_mut().chunks_mut(n))
            .map(|(((color, normal), face_normal), object)| TexelMaps {
                color,
                normal,
                face_normal,
                position: positions.as_mut().and_then(|p| p.next()),
                object,
            })
            .collect();
        (&mut self.gd, runs)
    }
}

/// What an impostor's maps hold before a resolve pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::impostor) enum MapsBefore {
    /// The result of an earlier resolve: every map is empty wherever `object` is
    /// [`NO_OBJECT`], so only texels with an object need clearing.
    Resolved,
    /// Zeros everywhere, fresh from [`zeroed_impostor`]: an empty texel only needs its object
    /// set to [`NO_OBJECT`], and the other maps' pages of empty rows are never touched.
    Zeroed,
}

/// A run's texels' `gd` and where the run starts, for a SPOC impostor: its rasterizer draws
/// triangles straight in the image and interpolates `gd` linearly there, while the SPOC's rays
/// curve, so the resolve moves each texel's `gd` to where its centre's ray meets the plane of
/// the stored triangle ([`Spoc::gd_on_plane`]). The texel's position, derived from its `gd`
/// ([`Impostor::position_at`]), is then on that plane, as the walk needs.
pub(super) struct RunDepth<'a> {
    pub(super) gd: &'a mut [f32],
    pub(super) first_pixel: usize,
    pub(super) spoc: &'a Spoc,
}

/// What resolving a visibility buffer needs besides the visible points.
pub(super) struct ResolveInputs<'a, F> {
    /// The impostor's camera (a copy: the impostor's maps are borrowed mutably meanwhile).
    pub(super) camera: ImpostorCamera,
    pub(super) mesh: &'a Mesh,
    pub(super) object: u32,
    pub(super) color: &'a F,
    pub(super) before: MapsBefore,
}

impl<'a, F> ResolveInputs<'a, F> {
    /// What resolving `mesh` (object id `object`) into `impostor`'s maps, which hold `before`,
    /// needs.
    pub(super) fn of(
        impostor: &Impostor,
        (mesh, object): (&'a Mesh, u32),
        color: &'a F,
        before: MapsBefore,
    ) -> Self {
        ResolveInputs {
            camera: impostor.camera.clone(),
            mesh,
            object,
            color,
            before,
        }
    }
}

/// Fills a run of texels — whole image rows of `width` texels — from the visible points
/// `visible(i)` of its texels `i` (counted from the run's start), and empties the texels with
/// none. Only the texels of `columns` (inclusive) in each row are resolved: every other one
/// is empty (`None`: all of them). `visible` must answer for every texel of the run, though:
/// texels ahead are asked for their triangle, to prefetch it. After it, every map is empty
/// wherever `object` is [`NO_OBJECT`].
pub(super) fn resolve_run<F, V>(
    run: &mut TexelMaps<'_>,
    (width, columns): (usize, Option<(usize, usize)>),
    mut depth: Option<RunDepth<'_>>,
    inputs: &ResolveInputs<'_, F>,
    visible: V,
) where
    F: Fn(&SurfaceSample) -> Vec3 + Sync,
    V: Fn(usize) -> Option<Visible>,
{
    let ResolveInputs {
        camera,
        mesh,
        object,
        color,
        before,
    } = inputs;
    let run_len = run.color.len();
    let mut colors = OpaquePacker::default();
    for row_start in (0..run_len).step_by(width) {
        let row_end = (row_start + width).min(run_len);
        // Outside the drawn columns every texel is empty, handled in bulk.
        let (x0, x1) = match columns {
            Some((c0, c1)) => (row_start + c0, (row_start + c1 + 1).min(row_end)),
            None => (row_start, row_start),
        };
        empty_texels(run, row_start..x0, *before);
        empty_texels(run, x1..row_end, *before);
        // The image row of this run row, for a SPOC's texel centres.
        let image_row = depth.as_ref().map_or(0.0, |d| {
            texel_centre(((d.first_pixel + row_start) / width) as f64)
        });
        for x in x0..x1 {
            // The triangles of texels a little ahead, on their way from memory (see
            // `crate::prefetch`): the triangle's indices first, its corners once they are here.
            // Ahead runs on into the next row, so that row's first texels are asked for too.
            let triangle_ahead = |k: usize| (x + k < run_len).then(|| visible(x + k)).flatten();
            if let Some(v) = triangle_ahead(TRIANGLE_AHEAD) {
                mesh.prefetch_triangle(v.triangle);
            }
            if let Some(v) = triangle_ahead(CORNERS_AHEAD) {
                mesh.prefetch_corners(v.triangle);
            }
            let Some(Visible {
                triangle: t,
                bary: b,
                frustum,
            }) = visible(x)
            else {
                empty_texels(run, x..x + 1, *before);
                continue;
            };
            let (s, face, interpolated) = surface_sample(mesh, t, b);
            run.color[x] = colors.pack(color(&s));
            run.normal[x] = pack_normal(interpolated, face);
            // The face normal, turned toward the camera.
            let toward = toward_viewer(camera, s.position.as_dvec3(), frustum);
            run.face_normal[x] = pack_unit(if face.as_dvec3().dot(toward) < 0.0 {
                -face
            } else {
                face
            });
            if let Some(d) = depth.as_mut() {
                let centre = DVec2::new(texel_centre((x - row_start) as f64), image_row);
                let (n, p) = (face.as_dvec3(), s.position.as_dvec3());
                if let Some(gd) = d.spoc.gd_on_plane(centre, n, p, d.gd[x] as f64) {
                    d.gd[x] = gd as f32;
                }
            }
            if let Some(position) = run.position.as_deref_mut() {
                position[x] = s.position;
            }
            run.object[x] = *object;
        }
    }
}

/// How many texels ahead [`resolve_run`] asks for a texel's triangle, and for its corners.
/// The triangle must have arrived when its corners are asked for.
pub(super) const TRIANGLE_AHEAD: usize = 10;
pub(super) const CORNERS_AHEAD: usize = 5;

/// Empties the texels `range` of `run`, whose maps hold `before`.
pub(super) fn empty_texels(
    run: &mut TexelMaps<'_>,
    range: std::ops::Range<usize>,
    before: MapsBefore,
) {
    match before {
        // Written, not read first: reading a fresh page maps the shared zero page, and the
        // write after it then pays a second fault.
        MapsBefore::Zeroed => run.object[range].fill(NO_OBJECT),
        // Only texels written last time need clearing: most of an impostor's image is empty,
        // and skipping it halves the pass.
        MapsBefore::Resolved => {
            for x in range {
                if run.object[x] != NO_OBJECT {
                    run.color[x] = HalfRgba::default();
                    run.normal[x] = OctUnit::default();
                    run.face_normal[x] = OctUnit::default();
                    if let Some(position) = run.position.as_deref_mut() {
                        position[x] = Vec3::ZERO;
                    }
                    run.object[x] = NO_OBJECT;
                }
            }
        }
    }
}

/// Fills the impostor's maps from the visible points `visible(i)` of texels `i` (row-major),
/// in parallel over rows (see [`resolve_run`]); its `gd` holds the depth as drawn.
pub(in crate::impostor) fn resolve<F, V>(
    impostor: &mut Impostor,
    (mesh, object): (&Mesh, u32),
    color: &F,
    before: MapsBefore,
    visible: V,
) where
    F: Fn(&SurfaceSample) -> Vec3 + Sync,
    V: Fn(usize) -> Option<Visible> + Sync,
{
    let row = impostor.color.size().0 as usize;
    let inputs = ResolveInputs::of(impostor, (mesh, object), color, before);
    let spoc = match &inputs.camera {
        ImpostorCamera::Spoc(s) => Some(s),
        _ => None,
    };
    let (gd, runs) = impostor.gd_and_texel_runs(row);
    gd.pixels_mut()
        .par_chunks_mut(row)
        .zip(runs)
        .enumerate()
        .for_each(|(y, (gd, mut run))| {
            let whole_row = (row, Some((0, row - 1)));
            // Through a SPOC, each texel's drawn `gd` is moved onto its triangle's plane, as
            // a build's bands are.
            let depth = spoc.map(|spoc| RunDepth {
                gd,
                first_pixel: y * row,
                spoc,
            });
            resolve_run(&mut run, whole_row, depth, &inputs, |x| {
                visible(y * row + x)
            });
        });
    finish_resolve(impostor, mesh);
}

/// Sets the bounds of a freshly resolved impostor (the mesh's box, padded) and drops what was
/// derived from its old maps.
pub(super) fn finish_resolve(impostor: &mut Impostor, mesh: &Mesh) {
    impostor.bounds = impostor_bounds(mesh);
    impostor.maps_changed();
}

/// The bounds of an impostor of `mesh`: the mesh's box padded by 10⁻⁴ of its largest extent.
pub(in crate::impostor) fn impostor_bounds(mesh: &Mesh) -> Aabb {
    let b = mesh.bounds();
    let pad = b.extent().max_element() * 1e-4;
    Aabb {
        min: b.min - Vec3::splat(pad),
        max: b.max + Vec3::splat(pad),
    }
}

/// An impostor sized for its camera whose maps are all zeros — object 0 everywhere, so not yet
/// a valid impostor: resolve it with [`MapsBefore::Zeroed`]. Its memory is not touched here
/// (see [`Image::zeroed`]): the parallel resolve takes the page faults, band by band.
pub(in crate::impostor) fn zeroed_impostor(camera: ImpostorCamera) -> Result<Impostor, FrameError> {
    let (w, h) = camera.resolution();
    crate::memory::check(
        || format!("a {w} × {h} impostor"),
        crate::memory::times(w as u64 * h as u64, crate::impostor::BYTES_PER_TEXEL),
    )?;
    // Allocated on two threads, half the bytes each (colour and normal; face normal, object
    // and gd): memory the allocator recycles (a process that builds again and again) it
    // clears itself, and that clearing then runs on both cores.
    let ((color, normal), (face_normal, object, gd)) = rayon::join(
        || (Image::zeroed(w, h), Image::zeroed(w, h)),
        || {
            (
                Image::zeroed(w, h),
                Image::zeroed(w, h),
                Image::zeroed(w, h),
            )
        },
    );
    let position = if camera.stores_positions() {
        Some(Image::zeroed(w, h)?)
    } else {
        None
    };
    Ok(Impostor::from_maps(
        camera,
        color?,
        gd?,
        normal?,
        face_normal?,
        position,
        object?,
        Aabb {
            min: Vec3::ZERO,
            max: Vec3::ZERO,
        },
    ))
}

/// The surface point with barycentrics `b` in triangle `t` of `m`.
/// Also returns the triangle's face normal `(p₁ − p₀) × (p₂ − p₀)` and the interpolated vertex
/// normal, neither normalized: the maps pack them, and packing normalizes ([`pack_normal`]).
// Inlined, like the other per-texel calls of `resolve_run` (`gd_on_plane`, `pack_rgba`, the
// prefetches, `toward_camera`): as calls, each handed its results back through memory and the
// texel's work could not be scheduled as one; inlining them cut the fresh SPOC build by about
// 7 % (`trompe bench`, the fresh SPOC line).
#[inline(always)]
pub(super) fn surface_sample(m: &Mesh, t: u32, b: Vec3) -> (SurfaceSample, Vec3, Vec3) {
    let [i0, i1, i2] = m.triangles[t as usize].map(|i| i as usize);
    let [p0, p1, p2] = [i0, i1, i2].map(|i| m.positions[i]);
    let position = p0 * b.x + p1 * b.y + p2 * b.z;
    let face = (p1 - p0).cross(p2 - p0);
    let interpolated = m.normals[i0] * b.x + m.normals[i1] * b.y + m.normals[i2] * b.z;
    // The colour callback may use the unit normal; when it does not, being inlined, this
    // square root and division are not computed at all.
    let normal = interpolated
        .try_normalize()
        .unwrap_or_else(|| face.normalize_or_zero());
    let uv = m
        .uvs
        .as_ref()
        .map_or(Vec2::ZERO, |uv| uv[i0] * b.x + uv[i1] * b.y + uv[i2] * b.z);
    let sample = SurfaceSample {
        position,
        normal,
        uv,
        triangle: t,
    };
    (sample, face, interpolated)
}

/// The packed shading normal of a surface sample: its `interpolated` vertex normal, or the
/// triangle's `face` normal where that is zero — as [`surface_sample`]'s unit normal, but
/// without normalizing first, since the octahedral packing divides by the 1-norm anyway.
#[inline(always)]
pub(super) fn pack_normal(interpolated: Vec3, face: Vec3) -> OctUnit {
    match pack_unit(interpolated) {
        ZERO_UNIT => pack_unit(face),
        code => code,
    }
}

/// The direction from `p` toward the camera that sees it: through a graph camera, toward the
/// apex of the frustum that drew it when known.
pub(super) fn toward_viewer(
    camera: &ImpostorCamera,
    p: glam::DVec3,
    frustum: Option<u32>,
) -> glam::DVec3 {
    match (camera, frustum) {
        (ImpostorCamera::Graph(g), Some(j)) => g.frusta()[j as usize].apex - p,
        _ => camera.toward_camera(p),
    }
}

/// The source triangle and barycentrics of a fragment of sub-triangle `t` (or of `t` itself
/// when the mesh was not tessellated).
pub(in crate::impostor) fn to_source(
    source: Option<&[SourceTriangle]>,
    t: u32,
    bary: Vec3,
) -> Visible {
    let (triangle, bary) = match source {
        Some(src) => {
            let (s, c) = src[t as usize];
            (s, c[0] * bary.x + c[1] * bary.y + c[2] * bary.z)
        }
        None => (t, bary),
    };
    Visible {
        triangle,
        bary,
        frustum: None,
    }
}
