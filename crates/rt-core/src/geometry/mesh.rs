//! Triangle meshes loaded from Wavefront OBJ files.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use thiserror::Error;

use crate::geometry::aabb::Aabb;
use crate::geometry::hit::PrimitiveHit;
use crate::geometry::method::TriangleMethod;
use crate::geometry::surface::SurfacePoint;
use crate::geometry::triangle::{TriangleRay, geometric_normal, intersect_by, triangle_surface_point};
use crate::math::ray::{Interval, Ray};
use crate::math::real::{Real, Vec3, narrow, normalize_robust, to_f32, to_f64, widen};

/// Most triangles one mesh may have (after fanning faces): 2²⁶ ≈ 67 M.
pub const MAX_MESH_TRIANGLES: usize = 1 << 26;
/// Largest OBJ file read, checked before reading: 2 GiB, about what 2²⁶
/// triangles take as text. tobj holds the parsed file in memory, so this
/// bounds the memory a scene can make the loader allocate.
pub const MAX_OBJ_BYTES: u64 = 1 << 31;

/// Why an OBJ file cannot be used as a mesh.
#[derive(Debug, Error)]
pub enum MeshError {
    /// The file cannot be opened (the OS's reason).
    #[error("cannot open OBJ file {path}: {reason}")]
    Open {
        /// The OBJ file.
        path: PathBuf,
        /// Why (in the message, so not also a `source()`).
        reason: std::io::Error,
    },
    /// The file is not valid OBJ (tobj's reason).
    #[error("cannot load OBJ file {path}: {reason}")]
    Load {
        /// The OBJ file.
        path: PathBuf,
        /// What tobj reported.
        reason: tobj::LoadError,
    },
    /// The file has no faces with three or more corners.
    #[error("OBJ file {0} has no triangles or polygons")]
    Empty(PathBuf),
    /// A vertex is NaN or infinite (after the mesh's transform).
    #[error("OBJ file {path}: vertex {index} is not finite")]
    NotFinite {
        /// The OBJ file.
        path: PathBuf,
        /// 0-based vertex index in the file.
        index: usize,
    },
    /// The file is larger than [`MAX_OBJ_BYTES`].
    #[error("OBJ file {path} is {bytes} bytes, more than the limit of {limit}")]
    FileTooLarge {
        /// The OBJ file.
        path: PathBuf,
        /// Its size.
        bytes: u64,
        /// The limit it exceeds.
        limit: u64,
    },
    /// More than [`MAX_MESH_TRIANGLES`] triangles.
    #[error("OBJ file {path} has {count} triangles, more than the limit of {MAX_MESH_TRIANGLES}")]
    TooLarge {
        /// The OBJ file.
        path: PathBuf,
        /// Triangle count after fanning.
        count: usize,
    },
}

/// A triangle mesh: shared vertex positions and triangles as index triples.
///
/// Triangle `i` is the i-th triangle in file order, faces of more than three
/// corners fanned in order into `(v0, v1, v2), (v0, v2, v3), …`. Its normal is
/// `normalize((b−a)×(c−a))`. Zero-area triangles keep their index but are
/// never hit.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Per-triangle unit normal; zero for a degenerate triangle.
    normals: Vec<Vec3>,
    bounds: Aabb,
    /// Boxed: most meshes have none, and every `Primitive` is as large as
    /// a mesh (inline, these two lists made it 144 bytes instead of 104).
    attributes: Option<Box<VertexAttributes>>,
}

/// A mesh's per-vertex attributes.
#[derive(Clone, Debug, Default, PartialEq)]
struct VertexAttributes {
    /// Shading normals (the file's `vn`), empty when it has none; a zero
    /// entry is a vertex without one.
    normals: Vec<Vec3>,
    /// Texture coordinates `(u, v)` with `v` down the image
    /// ([`crate::materials::texture`]), empty when the file has none.
    uvs: Vec<[f32; 2]>,
    /// A second set of texture coordinates (glTF's `TEXCOORD_1`), empty
    /// when the file has none.
    uvs1: Vec<[f32; 2]>,
    /// Tangents `(x, y, z, w)` for normal maps ([`Mesh::tangent`]), empty
    /// when there are none; a zero `(x, y, z)` is a vertex without one.
    tangents: Vec<[f32; 4]>,
}

/// A mesh's arrays, borrowed as they are stored: what a scene cache
/// writes, and [`Mesh::from_arrays`] takes back. Each vertex list is
/// empty or one entry per position.
#[derive(Clone, Copy, Debug)]
pub struct MeshArrays<'a> {
    /// Vertex positions.
    pub positions: &'a [Vec3],
    /// Index triples into `positions`.
    pub triangles: &'a [[u32; 3]],
    /// Per-triangle unit normals (zero for a degenerate triangle).
    pub normals: &'a [Vec3],
    /// The box around every triangle.
    pub bounds: Aabb,
    /// Per-vertex shading normals.
    pub vertex_normals: &'a [Vec3],
    /// Texture coordinates, set 0.
    pub uvs: &'a [[f32; 2]],
    /// Texture coordinates, set 1.
    pub uvs1: &'a [[f32; 2]],
    /// Tangents `(x, y, z, w)`.
    pub tangents: &'a [[f32; 4]],
}

impl Mesh {
    /// A mesh from positions and index triples. Returns `None` if there are no
    /// triangles or an index is out of range.
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Option<Self> {
        // In parallel: for a million triangles these passes take longer
        // than reading them.
        let out_of_range =
            |chunk: &[[u32; 3]]| chunk.iter().flatten().any(|&i| i as usize >= positions.len());
        if triangles.is_empty() || triangles.par_chunks(4096).any(out_of_range) {
            return None;
        }
        let normals = triangles
            .par_iter()
            .with_min_len(4096)
            .map(|&[a, b, c]| {
                let p = |i: u32| positions[i as usize];
                geometric_normal(p(a), p(b), p(c)).unwrap_or(Vec3::ZERO)
            })
            .collect();
        let bounds = triangles
            .par_chunks(4096)
            .map(|chunk| Aabb::from_points(chunk.iter().flatten().map(|&i| positions[i as usize])))
            .reduce(
                || None,
                |a, b| match (a, b) {
                    (Some(a), Some(b)) => Some(a.union(b)),
                    (a, b) => a.or(b),
                },
            )?;
        Some(Self { positions, triangles, normals, bounds, attributes: None })
    }

    /// The mesh's arrays as stored, for a scene cache.
    pub fn arrays(&self) -> MeshArrays<'_> {
        let a = self.attributes.as_deref();
        MeshArrays {
            positions: &self.positions,
            triangles: &self.triangles,
            normals: &self.normals,
            bounds: self.bounds,
            vertex_normals: a.map_or(&[], |a| &a.normals),
            uvs: a.map_or(&[], |a| &a.uvs),
            uvs1: a.map_or(&[], |a| &a.uvs1),
            tangents: a.map_or(&[], |a| &a.tangents),
        }
    }

    /// A mesh from the arrays [`Mesh::arrays`] gave, taken as they are
    /// (nothing recomputed, so the mesh is the one stored bit for bit).
    /// `None` unless every index is in range and every list has its
    /// length: one normal per triangle, each vertex list empty or one
    /// entry per position.
    #[allow(clippy::too_many_arguments)]
    pub fn from_arrays(
        positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
        normals: Vec<Vec3>,
        bounds: Aabb,
        vertex_normals: Vec<Vec3>,
        uvs: Vec<[f32; 2]>,
        uvs1: Vec<[f32; 2]>,
        tangents: Vec<[f32; 4]>,
    ) -> Option<Self> {
        let n = positions.len();
        let fits = |len: usize| len == 0 || len == n;
        let in_range = triangles.par_chunks(4096).all(|c| c.iter().flatten().all(|&i| (i as usize) < n));
        if triangles.is_empty()
            || !in_range
            || normals.len() != triangles.len()
            || ![vertex_normals.len(), uvs.len(), uvs1.len(), tangents.len()].into_iter().all(fits)
        {
            return None;
        }
        let none = vertex_normals.is_empty() && uvs.is_empty() && uvs1.is_empty() && tangents.is_empty();
        let attributes =
            (!none).then(|| Box::new(VertexAttributes { normals: vertex_normals, uvs, uvs1, tangents }));
        Some(Self { positions, triangles, normals, bounds, attributes })
    }

    /// The mesh with per-vertex shading normals and texture coordinates
    /// (each list empty, or one entry per vertex). Normals are normalised
    /// here; a zero or non-finite one marks a vertex without a normal.
    /// `None` if a list has the wrong length.
    pub fn with_vertex_attributes(mut self, normals: Vec<Vec3>, uvs: Vec<[f32; 2]>) -> Option<Self> {
        let fits = |n: usize| n == 0 || n == self.positions.len();
        if !fits(normals.len()) || !fits(uvs.len()) {
            return None;
        }
        if normals.is_empty() && uvs.is_empty() {
            self.attributes = None;
            return Some(self);
        }
        let normals = normals
            .into_par_iter()
            .with_min_len(4096)
            .map(|n| normalize_robust(n).unwrap_or(Vec3::ZERO))
            .collect();
        self.attributes =
            Some(Box::new(VertexAttributes { normals, uvs, uvs1: Vec::new(), tangents: Vec::new() }));
        Some(self)
    }

    /// The mesh with a second set of texture coordinates (glTF's
    /// `TEXCOORD_1`; empty, or one per vertex), `v` down the image as for
    /// the first. `None` if the list has the wrong length.
    pub fn with_second_uvs(mut self, uvs1: Vec<[f32; 2]>) -> Option<Self> {
        if !(uvs1.is_empty() || uvs1.len() == self.positions.len()) {
            return None;
        }
        if !uvs1.is_empty() {
            self.attributes.get_or_insert_with(Box::default).uvs1 = uvs1;
        } else if let Some(a) = &mut self.attributes {
            a.uvs1 = uvs1;
        }
        Some(self)
    }

    /// The mesh with per-vertex tangents `(x, y, z, w)` (glTF's `TANGENT`:
    /// `(x, y, z)` along increasing `u`, `w` = ±1 the handedness, so that
    /// the bitangent `w·(N × T)` points up the image; see
    /// [`crate::materials::normal_map`]), empty or one per vertex. A zero or
    /// non-finite `(x, y, z)` marks a vertex without one, which
    /// [`Mesh::with_generated_tangents`] fills in; `w` is taken by its sign.
    /// `None` if the list has the wrong length.
    pub fn with_tangents(mut self, tangents: Vec<[f32; 4]>) -> Option<Self> {
        if tangents.is_empty() {
            if let Some(a) = &mut self.attributes {
                a.tangents.clear();
            }
            return Some(self);
        }
        if tangents.len() != self.positions.len() {
            return None;
        }
        let tangents = tangents
            .into_iter()
            .map(|[x, y, z, w]| {
                let t = glam::Vec3::new(x, y, z);
                match t.try_normalize() {
                    Some(t) if t.is_finite() => [t.x, t.y, t.z, if w < 0.0 { -1.0 } else { 1.0 }],
                    _ => [0.0; 4],
                }
            })
            .collect();
        self.attributes.get_or_insert_with(Default::default).tangents = tangents;
        Some(self)
    }

    /// Whether the mesh has per-vertex tangents (for normal maps).
    pub fn has_tangents(&self) -> bool {
        !self.vertex_tangents().is_empty()
    }

    fn vertex_tangents(&self) -> &[[f32; 4]] {
        self.attributes.as_ref().map_or(&[], |a| &a.tangents)
    }

    /// The mesh with a tangent at every vertex that has none (all of them
    /// when it has none at all), made by MikkTSpace (Mikkelsen, "Simulation
    /// of Wrinkled Surfaces Revisited", 2008: the tangent space glTF 2.0
    /// and Blender bake normal maps in, so a map baked elsewhere reads back
    /// the same), from the positions, the shading normals (the facet's
    /// where a vertex has none) and the texture coordinates. Tangents the
    /// mesh has are kept. A mesh without texture coordinates is returned
    /// as it is; vertices MikkTSpace leaves without a tangent (on
    /// triangles with zero-area coordinates and no neighbour to borrow
    /// from) keep none, and the normal map falls back to any frame there.
    pub fn with_generated_tangents(self) -> Self {
        self.with_generated_tangents_of_set(0)
    }

    /// [`Mesh::with_generated_tangents`] from texture-coordinate set `set`
    /// (`TEXCOORD_set`): a normal map's tangent space follows the set the
    /// map is read through (glTF's `normalTexture.texCoord`). A mesh
    /// without that set is returned as it is.
    pub fn with_generated_tangents_of_set(self, set: u32) -> Self {
        if !self.has_uv_set(set)
            || (self.has_tangents() && self.vertex_tangents().iter().all(|t| t[..3] != [0.0; 3]))
        {
            return self;
        }
        let mut generated = MikkInput { mesh: &self, set, tangents: vec![[0.0; 4]; self.positions.len()] };
        // The crate's error type has no values: generation cannot fail.
        let _ = bevy_mikktspace::generate_tangents(&mut generated);
        let mut tangents = generated.tangents;
        for (t, old) in tangents.iter_mut().zip(self.vertex_tangents()) {
            if old[..3] != [0.0; 3] {
                *t = *old;
            }
        }
        self.with_tangents(tangents).expect("one tangent per vertex")
    }

    /// The tangent `(T, w)` at `p` on triangle `i` (a unit vector along
    /// increasing `u` and the handedness ±1, see [`Mesh::with_tangents`]):
    /// the corners' tangents weighted by `p`'s barycentric coordinates, and
    /// the sign of their weighted `w`. `None` when the mesh has none, a
    /// corner lacks one, or they cancel.
    pub fn tangent(&self, i: usize, p: Vec3) -> Option<(Vec3, f32)> {
        let tangents = self.vertex_tangents();
        if tangents.is_empty() {
            return None;
        }
        let corners = self.triangles[i].map(|v| tangents[v as usize].map(f64::from));
        if corners.iter().any(|c| c[..3] == [0.0; 3]) {
            return None;
        }
        let b = self.barycentric(i, p);
        let at = |k: usize| b[0] * corners[0][k] + b[1] * corners[1][k] + b[2] * corners[2][k];
        let t = normalize_robust(narrow(glam::DVec3::new(at(0), at(1), at(2))))?;
        Some((t, if at(3) < 0.0 { -1.0 } else { 1.0 }))
    }

    /// The meshes as one: their vertices and triangles one after another
    /// (vertex attributes kept where any mesh has them). `None` if there
    /// are none or the vertices overflow 32-bit indices.
    pub fn concat(mut meshes: Vec<Mesh>) -> Option<Self> {
        if meshes.len() == 1 {
            return meshes.pop();
        }
        let normals = meshes.iter().any(Mesh::has_vertex_normals);
        let uvs = meshes.iter().any(Mesh::has_uvs);
        let uvs1 = meshes.iter().any(|m| !m.uvs_of_set(1).is_empty());
        let tangents = meshes.iter().any(Mesh::has_tangents);
        let mut all = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut all_uvs1 = Vec::new();
        let mut all_tangents = Vec::new();
        for m in meshes {
            let base = u32::try_from(all.0.len()).ok()?;
            let n = m.positions.len();
            all.1.extend(m.triangles.iter().map(|t| t.map(|i| base + i)));
            all.0.extend(m.positions);
            let a = m.attributes.map(|a| *a).unwrap_or_default();
            if normals {
                all.2.extend(if a.normals.is_empty() { vec![Vec3::ZERO; n] } else { a.normals });
            }
            if uvs {
                all.3.extend(if a.uvs.is_empty() { vec![[0.0; 2]; n] } else { a.uvs });
            }
            if uvs1 {
                all_uvs1.extend(if a.uvs1.is_empty() { vec![[0.0; 2]; n] } else { a.uvs1 });
            }
            if tangents {
                all_tangents.extend(if a.tangents.is_empty() { vec![[0.0; 4]; n] } else { a.tangents });
            }
        }
        u32::try_from(all.0.len()).ok()?;
        Self::new(all.0, all.1)?
            .with_vertex_attributes(all.2, all.3)?
            .with_second_uvs(all_uvs1)?
            .with_tangents(all_tangents)
    }

    /// Loads an OBJ file with tobj as one mesh, then scales every vertex by
    /// `scale` about the origin and moves it by `translate`
    /// (`p' = scale·p + translate`). Vertex normals (`vn`) become shading
    /// normals and texture coordinates (`vt`) are kept, `v` flipped to point
    /// down the image; points, lines and materials are ignored (see
    /// [`Mesh::load_obj_parts`] for the materials).
    pub fn load_obj(path: &Path, scale: Real, translate: Vec3) -> Result<Self, MeshError> {
        Self::load_obj_limited(path, scale, translate, MAX_OBJ_BYTES)
    }

    fn load_obj_limited(path: &Path, scale: Real, translate: Vec3, limit: u64) -> Result<Self, MeshError> {
        let file = ObjFile::read(path, limit)?;
        let models: Vec<&tobj::Model> = file.models.iter().collect();
        mesh_of(path, &models, scale, translate)
    }

    /// Loads an OBJ file as one mesh per material (faces with no `usemtl`
    /// form a part without one), in the order each material is first used,
    /// with the materials its MTL files define, or why they could not be
    /// read. Transformed as by [`Mesh::load_obj`].
    pub fn load_obj_parts(path: &Path, scale: Real, translate: Vec3) -> Result<ObjParts, MeshError> {
        let file = ObjFile::read(path, MAX_OBJ_BYTES)?;
        let mut order: Vec<Option<usize>> = Vec::new();
        for model in &file.models {
            if !order.contains(&model.mesh.material_id) {
                order.push(model.mesh.material_id);
            }
        }
        let mut parts = Vec::new();
        for material in order {
            let models: Vec<&tobj::Model> =
                file.models.iter().filter(|m| m.mesh.material_id == material).collect();
            match mesh_of(path, &models, scale, translate) {
                Ok(mesh) => parts.push((mesh, material)),
                // A material whose faces are all points or lines has no part.
                Err(MeshError::Empty(_)) => {}
                Err(e) => return Err(e),
            }
        }
        if parts.is_empty() {
            return Err(MeshError::Empty(path.to_owned()));
        }
        Ok(ObjParts { parts, materials: file.materials, mtl_files: file.mtl_files })
    }

    /// Bytes of vertex positions, index triples, per-triangle normals and
    /// vertex attributes.
    pub fn memory_bytes(&self) -> usize {
        self.positions.len() * size_of::<Vec3>()
            + self.triangles.len() * size_of::<[u32; 3]>()
            + self.normals.len() * size_of::<Vec3>()
            + size_of_val(self.vertex_normals())
            + size_of_val(self.uvs())
            + size_of_val(self.uvs_of_set(1))
            + size_of_val(self.vertex_tangents())
    }

    /// Whether the mesh has per-vertex shading normals.
    pub fn has_vertex_normals(&self) -> bool {
        !self.vertex_normals().is_empty()
    }

    fn vertex_normals(&self) -> &[Vec3] {
        self.attributes.as_ref().map_or(&[], |a| &a.normals)
    }

    fn uvs(&self) -> &[[f32; 2]] {
        self.attributes.as_ref().map_or(&[], |a| &a.uvs)
    }

    /// Texture-coordinate set `set` (0 or 1; empty for any other or when
    /// the mesh has none).
    fn uvs_of_set(&self, set: u32) -> &[[f32; 2]] {
        match (set, self.attributes.as_ref()) {
            (0, Some(a)) => &a.uvs,
            (1, Some(a)) => &a.uvs1,
            _ => &[],
        }
    }

    /// Whether the mesh has texture-coordinate set `set` (`TEXCOORD_set`).
    pub fn has_uv_set(&self, set: u32) -> bool {
        !self.uvs_of_set(set).is_empty()
    }

    /// Whether the mesh has texture coordinates.
    pub fn has_uvs(&self) -> bool {
        !self.uvs().is_empty()
    }

    /// Number of triangles, degenerate ones included.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }
    /// The corners of triangle `i`.
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        self.triangles[i].map(|v| self.positions[v as usize])
    }
    /// Unit normal of triangle `i`, or zero if it is degenerate.
    pub fn normal(&self, i: usize) -> Vec3 {
        self.normals[i]
    }
    /// Bytes of the list of triangle normals.
    pub fn normal_list_bytes(&self) -> usize {
        std::mem::size_of_val(self.normals.as_slice())
    }
    /// Asks the CPU to start loading [`Mesh::normal`]`(i)` into the cache
    /// (no effect on results; nothing where the target has no prefetch).
    #[inline(always)]
    pub fn prefetch_normal(&self, i: usize) {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: prefetching never faults, whatever the address.
        unsafe {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            _mm_prefetch::<_MM_HINT_T0>(self.normals.as_ptr().wrapping_add(i) as *const i8);
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = i;
    }
    /// Whether the mesh bounds a volume, with its faces wound outward, as a
    /// translucent object's must: every edge belongs to exactly two faces,
    /// which run along it in opposite directions (so the winding is
    /// consistent), and the signed volume `Σ a·(b×c)/6` is positive (so
    /// the normals `(b−a)×(c−a)` point out). Vertices are compared by
    /// position, so files that repeat a position for each face pass too.
    /// The error says what is wrong, naming an edge by its corners.
    pub fn closed(&self) -> Result<(), String> {
        use std::collections::HashMap;
        // +0.0 and −0.0 are one position.
        let key = |p: Vec3| p.to_array().map(|c| to_f64(c) + 0.0).map(f64::to_bits);
        let mut ids = HashMap::new();
        let id: Vec<usize> = self
            .positions
            .iter()
            .map(|&p| {
                let next = ids.len();
                *ids.entry(key(p)).or_insert(next)
            })
            .collect();
        // Directed edges (from, to) and how often each occurs.
        let mut edges: HashMap<(usize, usize), u32> = HashMap::new();
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| id[i as usize]);
            for edge in [(a, b), (b, c), (c, a)] {
                *edges.entry(edge).or_insert(0) += 1;
            }
        }
        let corner = |i: usize| {
            let j = id.iter().position(|&k| k == i).expect("an id comes from a vertex");
            self.positions[j]
        };
        let mut sorted: Vec<_> = edges.iter().collect();
        sorted.sort();
        for (&(a, b), &n) in sorted {
            if n > 1 {
                return Err(format!(
                    "{n} faces run along the edge from {} to {} in the same direction (a seam, or \
                     faces wound inconsistently)",
                    corner(a),
                    corner(b)
                ));
            }
            if !edges.contains_key(&(b, a)) {
                return Err(format!(
                    "the edge from {} to {} belongs to one face only (a hole)",
                    corner(a),
                    corner(b)
                ));
            }
        }
        let volume: f64 = (0..self.triangle_count())
            .map(|i| {
                let [a, b, c] = self.triangle(i).map(|p| glam::DVec3::from(p.to_array().map(to_f64)));
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        if volume <= 0.0 {
            return Err(format!("its faces are wound inward (signed volume {volume:.3e})"));
        }
        Ok(())
    }

    /// The box around all triangles.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// `p` (a computed hit on triangle `i`) projected onto its plane:
    /// see [`triangle_surface_point`].
    pub fn surface_point(&self, i: usize, p: Vec3) -> SurfacePoint {
        triangle_surface_point(self.triangle(i), self.normals[i], p)
    }

    /// The barycentric coordinates `(b₀, b₁, b₂)` of `p` (a point on
    /// triangle `i`'s plane) with respect to its corners:
    /// `p = b₀·a + b₁·b + b₂·c`, from the areas of the sub-triangles
    /// (Cramer's rule on the edge vectors; pbrt-v4 §6.5.3 gets the same
    /// weights from its edge functions). Computed in f64, so they are good
    /// to about 1e-7 relative for f32 hits; they only weigh vertex
    /// attributes, never decide a hit.
    pub fn barycentric(&self, i: usize, p: Vec3) -> [f64; 3] {
        let [a, b, c] = self.triangle(i).map(widen);
        let (e1, e2, d) = (b - a, c - a, widen(p) - a);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (d1p, d2p) = (e1.dot(d), e2.dot(d));
        let det = d11 * d22 - d12 * d12;
        if !(det > 0.0 && det.is_finite()) {
            return [1.0, 0.0, 0.0];
        }
        let b1 = (d22 * d1p - d12 * d2p) / det;
        let b2 = (d11 * d2p - d12 * d1p) / det;
        [1.0 - b1 - b2, b1, b2]
    }

    /// The shading normal at `p` on triangle `i`: the vertex normals
    /// weighted by `p`'s barycentric coordinates and normalised (Phong
    /// shading), or `None` when the mesh has none, a corner lacks one, or
    /// they cancel.
    pub fn shading_normal(&self, i: usize, p: Vec3) -> Option<Vec3> {
        let normals = self.vertex_normals();
        if normals.is_empty() {
            return None;
        }
        let corners = self.triangles[i].map(|v| widen(normals[v as usize]));
        if corners.contains(&glam::DVec3::ZERO) {
            return None;
        }
        let [b0, b1, b2] = self.barycentric(i, p);
        normalize_robust(narrow(b0 * corners[0] + b1 * corners[1] + b2 * corners[2]))
    }

    /// The texture coordinates at `p` on triangle `i`, interpolated like
    /// the normals; `None` when the mesh has none.
    pub fn uv(&self, i: usize, p: Vec3) -> Option<(Real, Real)> {
        self.uv_of_set(i, 0, p)
    }

    /// The coordinates of texture-coordinate set `set` at `p` on triangle
    /// `i` ([`Mesh::uv`] for set 0); `None` when the mesh has no such set.
    pub fn uv_of_set(&self, i: usize, set: u32, p: Vec3) -> Option<(Real, Real)> {
        let uvs = self.uvs_of_set(set);
        if uvs.is_empty() {
            return None;
        }
        let corners = self.triangles[i].map(|v| uvs[v as usize].map(f64::from));
        let [b0, b1, b2] = self.barycentric(i, p);
        let at = |k: usize| (b0 * corners[0][k] + b1 * corners[1][k] + b2 * corners[2][k]) as Real;
        Some((at(0), at(1)))
    }

    /// The ratio of triangle `i`'s area in texture-coordinate set `set` to
    /// its area in the world, `|Δuv₀₁ × Δuv₀₂| / |Δp₀₁ × Δp₀₂|`: how many
    /// units of texture area a unit of surface covers, for choosing a
    /// mip-map level ([`crate::materials::texture_lod`]). 0 for a
    /// degenerate triangle or a missing set.
    pub fn uv_per_world_area(&self, i: usize, set: u32) -> f32 {
        let uvs = self.uvs_of_set(set);
        if uvs.is_empty() {
            return 0.0;
        }
        let [t0, t1, t2] = self.triangles[i].map(|v| uvs[v as usize].map(f64::from));
        let uv = ((t1[0] - t0[0]) * (t2[1] - t0[1]) - (t1[1] - t0[1]) * (t2[0] - t0[0])).abs();
        let [p0, p1, p2] = self.triangle(i).map(widen);
        let world = (p1 - p0).cross(p2 - p0).length();
        let ratio = uv / world;
        if ratio.is_finite() { ratio as f32 } else { 0.0 }
    }

    /// The tangents `(∂p/∂u, ∂p/∂v)` of triangle `i` along its texture
    /// coordinates: with `Δp₀₂ = p₀ − p₂`, `Δp₁₂ = p₁ − p₂` and the same
    /// differences of (u, v), the solution of `Δpᵢ₂ = Δuᵢ₂·∂p/∂u + Δvᵢ₂·∂p/∂v`
    /// (pbrt-v4 §6.5.3, `Triangle::InteractionFromIntersection`), in f64.
    /// `None` when the mesh has no coordinates or they do not span the
    /// triangle (a zero determinant, or parallel tangents).
    pub fn tangents(&self, i: usize) -> Option<(Vec3, Vec3)> {
        let uvs = self.uvs();
        if uvs.is_empty() {
            return None;
        }
        let [p0, p1, p2] = self.triangle(i).map(widen);
        let [t0, t1, t2] = self.triangles[i].map(|v| uvs[v as usize].map(f64::from));
        let (duv02, duv12) = ([t0[0] - t2[0], t0[1] - t2[1]], [t1[0] - t2[0], t1[1] - t2[1]]);
        let (dp02, dp12) = (p0 - p2, p1 - p2);
        let det = duv02[0] * duv12[1] - duv02[1] * duv12[0];
        if !(det != 0.0 && det.is_finite()) {
            return None;
        }
        let dpdu = (duv12[1] * dp02 - duv02[1] * dp12) / det;
        let dpdv = (duv02[0] * dp12 - duv12[0] * dp02) / det;
        let spans = dpdu.cross(dpdv).length_squared() > 0.0 && dpdu.is_finite() && dpdv.is_finite();
        spans.then(|| (narrow(dpdu), narrow(dpdv)))
    }

    /// The hit on triangle `i` alone with `t` in `range`. Degenerate
    /// triangles are never hit.
    pub fn intersect_triangle(
        &self,
        i: usize,
        ray: &TriangleRay,
        range: Interval,
        method: TriangleMethod,
    ) -> Option<PrimitiveHit> {
        let normal = self.normals[i];
        if normal == Vec3::ZERO {
            return None;
        }
        let [a, b, c] = self.triangle(i);
        let hit = intersect_by(method, a, b, c, ray, range)?;
        Some(PrimitiveHit { t: hit.t, primitive: i, normal })
    }

    /// The nearest triangle hit with `t` in `range`, by testing every triangle
    /// inside the mesh's bounding box: the reference the BVH is tested against.
    /// Ties keep the lower triangle index.
    pub fn intersect(&self, ray: &Ray, range: Interval) -> Option<PrimitiveHit> {
        self.intersect_with(ray, range, TriangleMethod::Watertight)
    }

    /// [`Mesh::intersect`] with the chosen triangle test.
    pub fn intersect_with(&self, ray: &Ray, range: Interval, method: TriangleMethod) -> Option<PrimitiveHit> {
        if !self.bounds.overlaps(ray, range) {
            return None;
        }
        let mut range = range;
        let mut closest = None;
        let ray = TriangleRay::new(ray);
        for i in 0..self.triangles.len() {
            if let Some(hit) = self.intersect_triangle(i, &ray, range, method) {
                range.max = hit.t;
                closest = Some(hit);
            }
        }
        closest
    }
}

/// A mesh as MikkTSpace reads it, and the tangents it writes back.
struct MikkInput<'m> {
    mesh: &'m Mesh,
    /// The texture-coordinate set the tangents follow.
    set: u32,
    tangents: Vec<[f32; 4]>,
}

impl bevy_mikktspace::Geometry for MikkInput<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.triangles.len()
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        let p = self.mesh.positions[self.mesh.triangles[face][vert] as usize];
        [p.x, p.y, p.z].map(to_f32)
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        let shading = self.mesh.vertex_normals().get(self.mesh.triangles[face][vert] as usize);
        let n = shading.copied().filter(|n| *n != Vec3::ZERO).unwrap_or(self.mesh.normals[face]);
        [n.x, n.y, n.z].map(to_f32)
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        // MikkTSpace's bitangent w·(N × T) follows increasing v; ours
        // points up the image, towards decreasing v (glTF's): give it −v.
        let [u, v] = self.mesh.uvs_of_set(self.set)[self.mesh.triangles[face][vert] as usize];
        [u, -v]
    }
    fn set_tangent(&mut self, tangent: Option<bevy_mikktspace::TangentSpace>, face: usize, vert: usize) {
        if let Some(t) = tangent {
            self.tangents[self.mesh.triangles[face][vert] as usize] = t.tangent_encoded();
        }
    }
}

/// An OBJ file split by material ([`Mesh::load_obj_parts`]).
#[derive(Debug)]
pub struct ObjParts {
    /// Each part's mesh, and the index of its material in `materials`
    /// (`None`: faces before any `usemtl`, or naming a material no MTL
    /// file defines).
    pub parts: Vec<(Mesh, Option<usize>)>,
    /// The materials of the file's MTL files (tobj's reading of them), or
    /// why they could not be read.
    pub materials: Result<Vec<tobj::Material>, String>,
    /// The MTL files the OBJ file names, whether they could be read or not.
    pub mtl_files: Vec<PathBuf>,
}

/// The `i`-th group of `width` values of `values`, if there is one.
fn nth(values: &[f32], i: u32, width: usize) -> Option<&[f32]> {
    values.get(width * i as usize..width * i as usize + width)
}

/// A parsed OBJ file: tobj's models and materials.
struct ObjFile {
    models: Vec<tobj::Model>,
    /// The MTL materials, or why they cannot be read.
    materials: Result<Vec<tobj::Material>, String>,
    /// The MTL files it names (read or not).
    mtl_files: Vec<PathBuf>,
}

impl ObjFile {
    fn read(path: &Path, limit: u64) -> Result<Self, MeshError> {
        // Opened here rather than by tobj, whose error says only "open file
        // failed": the OS's reason (no such file, permission denied) goes
        // into the message.
        let open = |reason| MeshError::Open { path: path.to_owned(), reason };
        let file = std::fs::File::open(path).map_err(open)?;
        let bytes = file.metadata().map_err(open)?.len();
        if bytes > limit {
            return Err(MeshError::FileTooLarge { path: path.to_owned(), bytes, limit });
        }
        let options = tobj::LoadOptions {
            triangulate: false, // We fan faces ourselves, in the order docs/conventions.md fixes.
            single_index: false,
            ignore_points: true,
            ignore_lines: true,
        };
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut reader = std::io::BufReader::new(file);
        let mtl_files = std::cell::RefCell::new(Vec::new());
        let mtl_problem = std::cell::RefCell::new(None);
        let (models, materials) = tobj::load_obj_buf(&mut reader, &options, |mtl| {
            mtl_files.borrow_mut().push(dir.join(mtl));
            load_mtl(&dir.join(mtl), &mut mtl_problem.borrow_mut())
        })
        .map_err(|reason| MeshError::Load { path: path.to_owned(), reason })?;
        let materials = materials.map_err(|e| mtl_problem.into_inner().unwrap_or_else(|| e.to_string()));
        Ok(Self { models, materials, mtl_files: mtl_files.into_inner() })
    }
}

/// Reads an MTL file with tobj, the colour statements (`Ka`, `Kd`, `Ks`,
/// `Ke`) checked first: the MTL specification lets one number stand for a
/// grey (`Kd 0.5` is `Kd 0.5 0.5 0.5`), which is written out in full here,
/// and tobj 4.0.5 panics on a colour of fewer than three numbers (it
/// unwraps their conversion into an array), so none or two are refused
/// here, the file and line put in `problem`, before tobj reads the file.
fn load_mtl(path: &Path, problem: &mut Option<String>) -> tobj::MTLLoadResult {
    let bytes = std::fs::read(path).map_err(|_| tobj::LoadError::OpenFileFailed)?;
    let Ok(text) = String::from_utf8(bytes) else {
        *problem = Some(format!("{}: not UTF-8 text", path.display()));
        return Err(tobj::LoadError::ReadError);
    };
    let mut checked = String::with_capacity(text.len() + 64);
    for (line_index, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if let Some(key @ ("Ka" | "Kd" | "Ks" | "Ke")) = words.next() {
            let values: Vec<&str> = words.collect();
            match values.len() {
                1 => {
                    checked.push_str(&format!("{key} {0} {0} {0}\n", values[0]));
                    continue;
                }
                0 | 2 => {
                    *problem = Some(format!(
                        "{} line {}: {key} gives {} numbers: a colour is 3 (r g b) or 1 (a grey)",
                        path.display(),
                        line_index + 1,
                        values.len()
                    ));
                    return Err(tobj::LoadError::MaterialParseError);
                }
                _ => {}
            }
        }
        checked.push_str(line);
        checked.push('\n');
    }
    tobj::load_mtl_buf(&mut checked.as_bytes())
}

/// One mesh from `models` of the OBJ file at `path`, transformed.
///
/// A vertex is a position, or, where the faces give normals or texture
/// coordinates, a distinct (position, normal, texture coordinate) triple:
/// positions are then repeated bit for bit, so shared edges stay shared
/// for the watertight test. A model whose faces give normals (or texture
/// coordinates) for only some corners gets none.
fn mesh_of(path: &Path, models: &[&tobj::Model], scale: Real, translate: Vec3) -> Result<Mesh, MeshError> {
    use std::collections::HashMap;
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let mut triangles = Vec::new();
    let any_normals = models.iter().any(|m| !m.mesh.normal_indices.is_empty());
    let any_uvs = models.iter().any(|m| !m.mesh.texcoord_indices.is_empty());
    let mut file_vertices = 0; // vertices of the models before this one
    for model in models {
        let m = &model.mesh;
        let mut local = Vec::with_capacity(m.positions.len() / 3);
        for (i, xyz) in m.positions.chunks_exact(3).enumerate() {
            let p = Vec3::new(xyz[0] as Real, xyz[1] as Real, xyz[2] as Real);
            let p = scale * p + translate;
            if !p.is_finite() {
                return Err(MeshError::NotFinite { path: path.to_owned(), index: file_vertices + i });
            }
            local.push(p);
        }
        file_vertices += local.len();
        let has_normals = m.normal_indices.len() == m.indices.len();
        let has_uvs = m.texcoord_indices.len() == m.indices.len();
        // Corner k of the model's faces → a vertex of the mesh.
        let corner_vertex: Vec<u32> = if !any_normals && !any_uvs {
            let base = positions.len() as u32;
            positions.extend_from_slice(&local);
            m.indices.iter().map(|&i| base + i).collect()
        } else {
            let mut seen: HashMap<(u32, u32, u32), u32> = HashMap::new();
            (0..m.indices.len())
                .map(|k| {
                    let n = if has_normals { m.normal_indices[k] } else { u32::MAX };
                    let t = if has_uvs { m.texcoord_indices[k] } else { u32::MAX };
                    *seen.entry((m.indices[k], n, t)).or_insert_with(|| {
                        positions.push(local[m.indices[k] as usize]);
                        // tobj checks the indices; a bad one would still only
                        // lose the attribute.
                        normals.push(match nth(&m.normals, n, 3) {
                            Some(n) if has_normals => Vec3::new(n[0] as Real, n[1] as Real, n[2] as Real),
                            _ => Vec3::ZERO,
                        });
                        // OBJ's v points up the image; ours down.
                        uvs.push(match nth(&m.texcoords, t, 2) {
                            Some(t) if has_uvs => [t[0], 1.0 - t[1]],
                            _ => [0.0, 0.0],
                        });
                        (positions.len() - 1) as u32
                    })
                })
                .collect()
        };
        let mut fan_face = |corners: &[u32]| {
            for k in 1..corners.len().saturating_sub(1) {
                triangles.push([corners[0], corners[k], corners[k + 1]]);
            }
        };
        if m.face_arities.is_empty() {
            corner_vertex.chunks_exact(3).for_each(&mut fan_face);
        } else {
            let mut start = 0;
            for &arity in &m.face_arities {
                let end = start + arity as usize;
                fan_face(&corner_vertex[start..end]);
                start = end;
            }
        }
        if triangles.len() > MAX_MESH_TRIANGLES {
            return Err(MeshError::TooLarge { path: path.to_owned(), count: triangles.len() });
        }
    }
    if !any_normals {
        normals.clear();
    }
    if !any_uvs {
        uvs.clear();
    }
    // tobj checks every index against the vertex count, so `new` only fails when empty.
    Mesh::new(positions, triangles)
        .and_then(|m| m.with_vertex_attributes(normals, uvs))
        .ok_or_else(|| MeshError::Empty(path.to_owned()))
}

/// The regular icosahedron centred at the origin: its 12 corners, the cyclic
/// permutations of `(0, ±1, ±φ)` with φ the golden ratio (circumradius
/// √(1 + φ²)), and its 20 faces as corner indices, each wound so that
/// `(b−a)×(c−a)` points outward. The seed of the icosphere of
/// `examples/gen_meshes.rs` and a closed mesh of `accuracy::hard_cases` (feature `accuracy`).
pub fn icosahedron() -> ([[f64; 3]; 12], [[u32; 3]; 20]) {
    let p = (1.0 + 5f64.sqrt()) / 2.0;
    let corners = [
        [-1.0, p, 0.0],
        [1.0, p, 0.0],
        [-1.0, -p, 0.0],
        [1.0, -p, 0.0],
        [0.0, -1.0, p],
        [0.0, 1.0, p],
        [0.0, -1.0, -p],
        [0.0, 1.0, -p],
        [p, 0.0, -1.0],
        [p, 0.0, 1.0],
        [-p, 0.0, -1.0],
        [-p, 0.0, 1.0],
    ];
    let faces = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    (corners, faces)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    const ALL: Interval = Interval::new(0.0, Real::INFINITY);

    fn obj(text: &str) -> tempfile::NamedTempFile {
        let mut f = tempfile::Builder::new().suffix(".obj").tempfile().unwrap();
        f.write_all(text.as_bytes()).unwrap();
        f
    }

    #[test]
    fn tangents_solve_the_edge_equations_of_the_texture_coordinates() {
        // For random triangles and texture coordinates, p₀ − p₂ and p₁ − p₂
        // are the (u, v) differences times (∂p/∂u, ∂p/∂v); coordinates that
        // do not span the triangle give none, as does a mesh without any.
        for k in 0..200u32 {
            let rng = &mut crate::sampling::sampler::SampleRng::new(k, 41, 0);
            let mut point = || {
                let ((a, b), (c, _)) = (rng.next_pair(), rng.next_pair());
                Vec3::new(a * 4.0 - 2.0, b * 4.0 - 2.0, c * 4.0 - 2.0)
            };
            let positions = vec![point(), point(), point()];
            let uvs: Vec<[f32; 2]> = (0..3)
                .map(|_| [crate::math::real::to_f32(point().x), crate::math::real::to_f32(point().y)])
                .collect();
            let Some(mesh) = Mesh::new(positions.clone(), vec![[0, 1, 2]]) else { continue };
            let mesh = mesh.with_vertex_attributes(Vec::new(), uvs.clone()).unwrap();
            let Some((dpdu, dpdv)) = mesh.tangents(0) else { continue };
            let uv = |i: usize| (uvs[i][0] as Real, uvs[i][1] as Real);
            for i in [0, 1] {
                let (du, dv) = (uv(i).0 - uv(2).0, uv(i).1 - uv(2).1);
                let rebuilt = dpdu * du + dpdv * dv;
                let edge = positions[i] - positions[2];
                assert!(
                    (rebuilt - edge).length() <= 1e-3 * (1.0 + edge.length()),
                    "triangle {k}, edge {i}: {rebuilt} for {edge}"
                );
            }
        }
        let flat = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
        assert_eq!(flat.tangents(0), None);
        let collinear =
            flat.with_vertex_attributes(Vec::new(), vec![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]).unwrap();
        assert_eq!(collinear.tangents(0), None);
    }

    /// The unit quad in z = 0 as two triangles wound towards +z, with
    /// texture coordinates `uv(x, y)` at its corners.
    fn quad(uv: impl Fn(f32, f32) -> [f32; 2]) -> Mesh {
        let corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
        let positions =
            corners.iter().map(|&(x, y)| narrow(glam::DVec3::new(x.into(), y.into(), 0.0))).collect();
        let uvs = corners.iter().map(|&(x, y)| uv(x, y)).collect();
        Mesh::new(positions, vec![[0, 1, 2], [0, 2, 3]])
            .unwrap()
            .with_vertex_attributes(Vec::new(), uvs)
            .unwrap()
    }

    #[test]
    fn mikktspace_tangents_follow_the_texture_coordinate_set_they_are_made_for() {
        // Set 0 runs u along +x, set 1 along +y (the image turned a quarter):
        // the tangents of set 1 run along +y, those of set 0 along +x.
        let at = Vec3::new(0.3, 0.6, 0.0);
        let with_both = || {
            let turned = [[0.0, 1.0], [0.0, 0.0], [1.0, 0.0], [1.0, 1.0]].to_vec();
            quad(|x, y| [x, 1.0 - y]).with_second_uvs(turned).unwrap()
        };
        let (t, _) = with_both().with_generated_tangents_of_set(1).tangent(0, at).unwrap();
        assert!((t - Vec3::Y).length() < 1e-6, "set 1: {t}");
        let (t, _) = with_both().with_generated_tangents_of_set(0).tangent(0, at).unwrap();
        assert!((t - Vec3::X).length() < 1e-6, "set 0: {t}");
        // A set the mesh lacks makes none.
        assert!(!quad(|x, y| [x, y]).with_generated_tangents_of_set(1).has_tangents());
    }

    #[test]
    fn mikktspace_tangents_of_a_quad_run_along_u_with_the_bitangent_up_the_image() {
        // u along +x, v down the image along −y (an image laid flat, its
        // top at +y): T = +x and w·(N × T) = w·(z × x) = w·y must point up
        // the image, +y, so w = +1. Mirrored in u, T = −x and w = −1.
        let at = Vec3::new(0.3, 0.6, 0.0);
        let normal = |m: &Mesh| m.normal(m.triangles.len() - 1);
        let m = quad(|x, y| [x, 1.0 - y]).with_generated_tangents();
        assert!(m.has_tangents() && normal(&m) == Vec3::Z);
        for i in 0..2 {
            let (t, w) = m.tangent(i, at).unwrap();
            assert!((t - Vec3::X).length() < 1e-6 && w == 1.0, "triangle {i}: {t} {w}");
        }
        let mirrored = quad(|x, y| [1.0 - x, 1.0 - y]).with_generated_tangents();
        let (t, w) = mirrored.tangent(1, at).unwrap();
        assert!((t + Vec3::X).length() < 1e-6 && w == -1.0, "{t} {w}");
        // Scaled and sheared coordinates: T still along ∂p/∂u's direction.
        let sheared = quad(|x, y| [2.0 * x + y, 1.0 - y]).with_generated_tangents();
        let (t, _) = sheared.tangent(0, at).unwrap();
        assert!((t - Vec3::X).length() < 1e-6, "{t}");
    }

    #[test]
    fn tangents_from_the_file_are_kept_and_only_missing_ones_generated() {
        let t = Vec3::new(1.0, 1.0, 0.0).normalize();
        let given = vec![[1.0, 1.0, 0.0, -1.0], [0.0; 4], [1.0, 1.0, 0.0, -1.0], [1.0, 1.0, 0.0, -1.0]];
        let m = quad(|x, y| [x, 1.0 - y]).with_tangents(given).unwrap();
        assert_eq!(m.tangent(0, Vec3::new(0.5, 0.2, 0.0)), None, "a corner has none yet");
        let (t0, w0) = m.tangent(1, Vec3::new(0.2, 0.5, 0.0)).unwrap();
        assert!((t0 - t).length() < 1e-6 && w0 == -1.0);
        let m = m.with_generated_tangents();
        let (t0, w0) = m.tangent(1, Vec3::new(0.2, 0.5, 0.0)).unwrap();
        assert!((t0 - t).length() < 1e-6 && w0 == -1.0, "kept: {t0} {w0}");
        let [x, y, z, w] = m.vertex_tangents()[1];
        assert!((x - 1.0).abs() < 1e-6 && y.abs() < 1e-6 && z.abs() < 1e-6 && w == 1.0, "generated");
        assert!(m.memory_bytes() > quad(|x, y| [x, y]).memory_bytes());
        assert_eq!(quad(|x, y| [x, y]).with_tangents(vec![[0.0; 4]; 3]), None, "one per vertex");
    }

    #[test]
    fn degenerate_texture_coordinates_give_finite_tangents_or_none_never_nan() {
        // Every corner at one (u, v), or all on a line: MikkTSpace has no
        // direction to give; what the mesh answers is finite or nothing.
        for uv in
            [|_: f32, _: f32| [0.5, 0.5], |x: f32, y: f32| [x + y, x + y], |x: f32, _: f32| [x, f32::NAN]]
        {
            let m = quad(uv).with_generated_tangents();
            for i in 0..2 {
                if let Some((t, w)) = m.tangent(i, Vec3::new(0.4, 0.3, 0.0)) {
                    assert!(t.is_finite() && (t.length() - 1.0).abs() < 1e-5 && w.abs() == 1.0, "{t} {w}");
                }
            }
        }
        // Without texture coordinates there is nothing to generate from.
        let flat = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
        assert!(!flat.with_generated_tangents().has_tangents());
    }

    #[test]
    fn a_quad_is_fanned_into_two_triangles_in_order() {
        // Quad (0,0,1) (1,0,1) (1,1,1) (0,1,1): fanned (v0,v1,v2), (v0,v2,v3).
        let f = obj("v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 1 2 3 4\n");
        let m = Mesh::load_obj(f.path(), 1.0, Vec3::ZERO).unwrap();
        assert_eq!(m.triangle_count(), 2);
        assert_eq!(
            m.triangle(1),
            [Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 1.0, 1.0), Vec3::new(0.0, 1.0, 1.0)]
        );
        // (1,0,0)×(1,1,0) = (0,0,1).
        assert_eq!(m.normal(0), Vec3::Z);
        // (0.2, 0.7) is above the diagonal: second triangle.
        let hit = m.intersect(&Ray::new(Vec3::new(0.2, 0.7, 0.0), Vec3::Z), ALL).unwrap();
        assert_eq!((hit.t, hit.primitive, hit.normal), (1.0, 1, Vec3::Z));
        let hit = m.intersect(&Ray::new(Vec3::new(0.7, 0.2, 0.0), Vec3::Z), ALL).unwrap();
        assert_eq!(hit.primitive, 0);
    }

    #[test]
    fn relative_indices_and_a_transform_are_applied() {
        let f = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n");
        let m = Mesh::load_obj(f.path(), 2.0, Vec3::new(0.0, 0.0, 5.0)).unwrap();
        assert_eq!(
            m.triangle(0),
            [Vec3::new(0.0, 0.0, 5.0), Vec3::new(2.0, 0.0, 5.0), Vec3::new(0.0, 2.0, 5.0)]
        );
    }

    #[test]
    fn the_nearest_of_several_triangles_wins_and_degenerate_ones_are_skipped() {
        // Triangle 0 is degenerate (collinear) but keeps its index; 1 at z=2, 2 at z=1.
        let f = obj("v 0 0 0\nv 1 0 0\nv 2 0 0\n\
             v -1 -1 2\nv 3 -1 2\nv -1 3 2\n\
             v -1 -1 1\nv 3 -1 1\nv -1 3 1\n\
             f 1 2 3\nf 4 5 6\nf 7 8 9\n");
        let m = Mesh::load_obj(f.path(), 1.0, Vec3::ZERO).unwrap();
        assert_eq!(m.normal(0), Vec3::ZERO);
        let hit = m.intersect(&Ray::new(Vec3::new(0.5, 0.0, -1.0), Vec3::Z), ALL).unwrap();
        assert_eq!((hit.t, hit.primitive), (2.0, 2));
    }

    #[test]
    fn missing_empty_and_out_of_range_files_are_errors() {
        let missing = Mesh::load_obj(Path::new("/nonexistent/x.obj"), 1.0, Vec3::ZERO).unwrap_err();
        assert!(matches!(missing, MeshError::Open { .. }));
        // The OS's reason and the path, not tobj's "open file failed".
        let message = missing.to_string();
        assert!(message.starts_with("cannot open OBJ file /nonexistent/x.obj: No such file"), "{message}");
        let empty = obj("# nothing\nv 0 0 0\n");
        assert!(matches!(Mesh::load_obj(empty.path(), 1.0, Vec3::ZERO), Err(MeshError::Empty(_))));
        let bad = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
        assert!(matches!(Mesh::load_obj(bad.path(), 1.0, Vec3::ZERO), Err(MeshError::Load { .. })));
        let zero = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
        assert!(matches!(Mesh::load_obj(zero.path(), 1.0, Vec3::ZERO), Err(MeshError::Load { .. })));
    }

    #[test]
    fn files_over_the_size_limit_are_refused_before_reading() {
        let f = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        let e = Mesh::load_obj_limited(f.path(), 1.0, Vec3::ZERO, 10).unwrap_err();
        assert!(matches!(e, MeshError::FileTooLarge { bytes: 32, limit: 10, .. }), "{e}");
        assert!(Mesh::load_obj_limited(f.path(), 1.0, Vec3::ZERO, 32).is_ok());
    }

    #[test]
    fn malformed_obj_text_is_an_error_not_a_panic() {
        for text in [
            "v 0 0 zero\nf 1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 -9 3\n",
            "f 1 2 3\n",
            "v 1 2\n",
            "\u{0}\u{1}garbage",
        ] {
            let f = obj(text);
            assert!(Mesh::load_obj(f.path(), 1.0, Vec3::ZERO).is_err(), "{text:?} loaded");
        }
    }

    #[test]
    fn every_ray_from_inside_a_closed_mesh_hits_an_outward_face() {
        // A regular octahedron |x| + |y| + |z| = 1 with faces wound outward:
        // from any interior point, every direction must hit (no leak through
        // an edge or vertex), on the face whose normal points along the ray.
        let f = obj("v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n\
             f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n");
        let m = Mesh::load_obj(f.path(), 1.0, Vec3::ZERO).unwrap();
        for i in 0..m.triangle_count() {
            let centroid = m.triangle(i).iter().copied().sum::<Vec3>() / 3.0;
            assert!(m.normal(i).dot(centroid) > 0.0, "face {i} is wound inward");
        }
        // Directions on a fine lattice, including exact vertex and edge directions.
        let origin = Vec3::new(0.01, -0.02, 0.015);
        let steps = 24;
        for i in -steps..=steps {
            for j in -steps..=steps {
                for k in [-steps, steps] {
                    for dir in [
                        Vec3::new(i as Real, j as Real, k as Real),
                        Vec3::new(k as Real, i as Real, j as Real),
                        Vec3::new(j as Real, k as Real, i as Real),
                    ] {
                        let hit = m.intersect(&Ray::new(origin, dir), ALL);
                        let hit = hit.unwrap_or_else(|| panic!("ray along {dir} leaked out"));
                        assert!(hit.normal.dot(dir) > 0.0);
                    }
                }
            }
        }
    }

    /// The icosahedron as a mesh, faces changed by `edit`.
    fn icosahedron_mesh(edit: impl FnOnce(&mut Vec<[u32; 3]>)) -> Mesh {
        let (corners, faces) = icosahedron();
        let positions = corners.iter().map(|c| Vec3::new(c[0] as Real, c[1] as Real, c[2] as Real)).collect();
        let mut faces = faces.to_vec();
        edit(&mut faces);
        Mesh::new(positions, faces).unwrap()
    }

    #[test]
    fn closed_meshes_are_told_from_open_inconsistent_and_inside_out_ones() {
        assert_eq!(icosahedron_mesh(|_| {}).closed(), Ok(()));
        let hole = icosahedron_mesh(|f| {
            f.pop();
        })
        .closed();
        assert!(hole.as_ref().is_err_and(|e| e.contains("one face only (a hole)")), "{hole:?}");
        let flipped_one = icosahedron_mesh(|f| f[3].swap(1, 2)).closed();
        assert!(flipped_one.as_ref().is_err_and(|e| e.contains("same direction")), "{flipped_one:?}");
        let inside_out = icosahedron_mesh(|f| f.iter_mut().for_each(|t| t.swap(1, 2))).closed();
        assert!(inside_out.as_ref().is_err_and(|e| e.contains("wound inward")), "{inside_out:?}");
        let doubled = icosahedron_mesh(|f| f.push(f[0])).closed();
        assert!(doubled.is_err(), "a face given twice");
        // A face per triangle with its own copies of the corners (as some
        // exporters write) is still closed: vertices are matched by position.
        let (corners, faces) = icosahedron();
        let positions: Vec<Vec3> = faces
            .iter()
            .flatten()
            .map(|&i| {
                Vec3::new(
                    corners[i as usize][0] as Real,
                    corners[i as usize][1] as Real,
                    corners[i as usize][2] as Real,
                )
            })
            .collect();
        let unshared = (0..20u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        assert_eq!(Mesh::new(positions, unshared).unwrap().closed(), Ok(()));
    }

    #[test]
    fn icosahedron_has_equal_edges_and_faces_wound_outward() {
        let (corners, faces) = icosahedron();
        let at = |i: u32| glam::DVec3::from_array(corners[i as usize]);
        for [a, b, c] in faces {
            let (a, b, c) = (at(a), at(b), at(c));
            assert!((b - a).cross(c - a).dot(a) > 0.0, "face {a} {b} {c} is wound inward");
            for edge in [b - a, c - b, a - c] {
                assert!((edge.length() - 2.0).abs() < 1e-12, "edge {edge}");
            }
        }
    }

    #[test]
    fn a_closed_mesh_far_from_the_origin_has_no_leaks_from_inside() {
        // The radius-2 icosphere at (148376, 1234, −223423):
        // 10 000 rays from its centre in directions spread over the sphere.
        let obj_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/meshes/icosphere.obj");
        let centre = Vec3::new(148376.0, 1234.0, -223423.0);
        let m = Mesh::load_obj(&obj_path, 2.0, centre).unwrap();
        let n = 100;
        for i in 0..n {
            for j in 0..n {
                let (u, v) = ((i as Real + 0.37) / n as Real, (j as Real + 0.61) / n as Real);
                let (theta, phi) = ((1.0 - 2.0 * u).acos(), 2.0 * std::f64::consts::PI as Real * v);
                let d = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                assert!(m.intersect(&Ray::new(centre, d), ALL).is_some(), "leak along {d}");
            }
        }
    }

    #[test]
    fn a_fine_grid_far_away_has_no_holes() {
        // 100 × 100 quads of 0.01 units (20 000 triangles) seen from 5000 units:
        // 5·10⁵ triangle sizes away. Every ray aimed into the grid must hit it.
        let grid = crate::testing::test_support::grid_mesh(100, |i, j| {
            Vec3::new(i as Real * 0.01, j as Real * 0.01, 0.0)
        });
        let eye = Vec3::new(0.3, 0.6, -5000.0);
        for k in 0..2000u32 {
            // Targets on a lattice that includes vertices and shared edges.
            let target =
                Vec3::new((k % 50) as Real * 0.02 + 0.005 * (k % 3) as Real, (k / 50) as Real * 0.025, 0.0);
            let hit = grid.intersect(&Ray::new(eye, target - eye), ALL);
            assert!(hit.is_some(), "ray to {target} slipped through the grid");
        }
    }

    #[test]
    fn vertex_normals_and_texture_coordinates_are_read_and_interpolated_at_a_hit() {
        // A unit quad in z = 0; normals tilt towards ±x, texture coordinates
        // span [0, 1]² with OBJ's v up.
        let f = obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
                     vn -1 0 -1\nvn 1 0 -1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                     f 1/1/1 2/2/2 3/3/2 4/4/1\n");
        let m = Mesh::load_obj(f.path(), 1.0, Vec3::ZERO).unwrap();
        assert!(m.has_vertex_normals() && m.has_uvs());
        assert_eq!(m.triangle_count(), 2);
        // Halfway across, the normals average to −z; a quarter of the way, a
        // quarter tilt.
        let n = m.shading_normal(0, Vec3::new(0.5, 0.25, 0.0)).unwrap();
        assert!((n - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6, "{n}");
        let n = m.shading_normal(1, Vec3::new(0.25, 0.5, 0.0)).unwrap();
        let want = Vec3::new(-0.5, 0.0, -1.0).normalize();
        assert!((n - want).length() < 1e-6, "{n}");
        // (x, y) → (u, 1 − v) = (x, 1 − y).
        let (u, v) = m.uv(1, Vec3::new(0.25, 0.75, 0.0)).unwrap();
        assert!((u - 0.25).abs() < 1e-6 && (v - 0.25).abs() < 1e-6, "{u} {v}");
        let b = m.barycentric(0, Vec3::new(0.75, 0.25, 0.0));
        assert!(
            (b[0] - 0.25).abs() < 1e-12 && (b[1] - 0.5).abs() < 1e-12 && (b[2] - 0.25).abs() < 1e-12,
            "{b:?}"
        );
        // Positions shared by corners with different normals stay bit-identical.
        assert_eq!(m.triangle(0)[0], m.triangle(1)[0]);
    }

    #[test]
    fn a_mesh_without_attributes_keeps_one_vertex_per_position_and_flat_shading() {
        let f = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        let m = Mesh::load_obj(f.path(), 1.0, Vec3::ZERO).unwrap();
        assert!(!m.has_vertex_normals() && !m.has_uvs());
        assert_eq!(m.shading_normal(0, Vec3::new(0.2, 0.2, 0.0)), None);
        assert_eq!(m.memory_bytes(), 3 * size_of::<Vec3>() + size_of::<[u32; 3]>() + size_of::<Vec3>());
    }

    #[test]
    fn meshes_concatenate_with_their_attributes_padded() {
        let a = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]])
            .unwrap()
            .with_vertex_attributes(vec![Vec3::Z; 3], Vec::new())
            .unwrap();
        let b = Mesh::new(vec![Vec3::ZERO, Vec3::Y, Vec3::Z], vec![[0, 1, 2]]).unwrap();
        let c = Mesh::concat(vec![a, b]).unwrap();
        assert_eq!(c.triangle_count(), 2);
        assert_eq!(c.triangle(1), [Vec3::ZERO, Vec3::Y, Vec3::Z]);
        assert!(c.shading_normal(0, Vec3::new(0.2, 0.2, 0.0)).is_some());
        assert_eq!(c.shading_normal(1, Vec3::new(0.0, 0.2, 0.2)), None);
        assert!(Mesh::concat(Vec::new()).is_none());
    }

    #[test]
    fn a_second_uv_set_is_kept_interpolated_and_its_area_ratio_measured() {
        // A 2×2 quad in z = 0: set 0 maps it onto the unit square, set 1
        // onto a quarter of it, turned.
        let quad = Mesh::new(
            vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(2.0, 2.0, 0.0),
                Vec3::new(0.0, 2.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
        .unwrap()
        .with_vertex_attributes(vec![], vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
        .unwrap();
        assert!(quad.has_uv_set(0) && !quad.has_uv_set(1));
        assert_eq!(quad.uv_of_set(0, 1, Vec3::new(1.0, 0.5, 0.0)), None);
        assert_eq!(quad.uv_per_world_area(0, 1), 0.0);
        let quad = quad.with_second_uvs(vec![[0.5, 0.0], [0.5, 0.5], [0.0, 0.5], [0.0, 0.0]]).unwrap();
        assert!(quad.has_uv_set(1));
        let p = Vec3::new(1.5, 0.5, 0.0);
        let (u, v) = quad.uv_of_set(0, 1, p).unwrap();
        assert!((u - 0.375).abs() < 1e-6 && (v - 0.375).abs() < 1e-6, "({u}, {v})");
        assert_eq!(quad.uv_of_set(0, 0, p), quad.uv(0, p));
        // Unit uv square over 4 world units; a quarter of it over 4.
        assert!((quad.uv_per_world_area(0, 0) - 0.25).abs() < 1e-6);
        assert!((quad.uv_per_world_area(1, 1) - 0.0625).abs() < 1e-6);
        assert_eq!(quad.with_second_uvs(vec![[0.0; 2]; 3]), None);
        // Kept when meshes are joined.
        let joined = Mesh::concat(vec![
            Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap(),
            Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]])
                .unwrap()
                .with_second_uvs(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
                .unwrap(),
        ])
        .unwrap();
        assert!(joined.has_uv_set(1) && !joined.has_uv_set(0));
        assert!((joined.uv_per_world_area(1, 1) - 1.0).abs() < 1e-6);
    }
}
