//! Mesh files named by `<mesh filename>`: STL (ASCII or binary, stl_io) and Wavefront OBJ
//! (tobj), scaled, as one triangle list. `package://pkg/rest` resolves to the nearest
//! directory named `pkg` above the URDF (the ROS package layout `pkg/urdf/robot.urdf`,
//! `pkg/meshes/…`); `file://` and plain paths are taken as they are, relative to the URDF.

use std::path::{Path, PathBuf};

/// A triangle mesh, metres.
#[derive(Debug, Clone, PartialEq)]
pub struct TriMesh {
    pub vertices: Vec<[f64; 3]>,
    /// Vertex indices, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Axis-aligned bounds (min, max) of the vertices.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for v in &self.vertices {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        (lo, hi)
    }
}

/// Loads `filename` (as written in the URDF) relative to `dir`, scaled per axis.
pub fn load(filename: &str, scale: [f64; 3], dir: &Path) -> Result<TriMesh, String> {
    if scale.iter().any(|s| !(s.is_finite() && *s != 0.0)) {
        return Err(format!(
            "<mesh filename=\"{filename}\" scale=\"{scale:?}\">: scale factors must be \
             non-zero numbers"
        ));
    }
    let path = resolve(filename, dir)?;
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let mut mesh = match ext.as_deref() {
        Some("stl") => read_stl(&path),
        Some("obj") => read_obj(&path),
        _ => Err("only STL and OBJ meshes are supported".to_string()),
    }
    .map_err(|e| format!("<mesh filename=\"{filename}\"> ({}): {e}", path.display()))?;
    for v in &mut mesh.vertices {
        for k in 0..3 {
            v[k] *= scale[k];
        }
    }
    if mesh.triangles.is_empty() {
        return Err(format!(
            "<mesh filename=\"{filename}\">: the mesh has no triangles"
        ));
    }
    // A part is at most 100 m across; a NaN or a 1e30 m vertex is named, not left to the
    // convex hull to fail on.
    let limit = crate::limits::MAX_PART_SIZE_M;
    if let Some(i) = mesh
        .vertices
        .iter()
        .position(|v| !v.iter().all(|c| c.abs() <= limit))
    {
        return Err(format!(
            "<mesh filename=\"{filename}\">: vertex {i} {:?} (scaled) is not finite or lies \
             more than {limit} m from the link frame",
            mesh.vertices[i]
        ));
    }
    Ok(mesh)
}

fn resolve(filename: &str, dir: &Path) -> Result<PathBuf, String> {
    if let Some(rest) = filename.strip_prefix("package://") {
        let (package, inner) = rest.split_once('/').unwrap_or((rest, ""));
        let base = dir
            .ancestors()
            .find(|a| a.file_name().is_some_and(|n| n == package))
            .ok_or_else(|| {
                format!(
                    "<mesh filename=\"{filename}\">: no directory named '{package}' above the \
                     URDF; give the mesh path relative to the URDF instead"
                )
            })?;
        return Ok(base.join(inner));
    }
    let plain = filename.strip_prefix("file://").unwrap_or(filename);
    Ok(dir.join(plain))
}

fn read_stl(path: &Path) -> Result<TriMesh, String> {
    let mut file = caravan::input::open_regular(path).map_err(|e| format!("cannot read: {e}"))?;
    let stl = stl_io::read_stl(&mut file).map_err(|e| format!("not a valid STL file: {e}"))?;
    Ok(TriMesh {
        vertices: stl
            .vertices
            .iter()
            .map(|v| [v[0] as f64, v[1] as f64, v[2] as f64])
            .collect(),
        triangles: stl
            .faces
            .iter()
            .map(|f| f.vertices.map(|i| i as u32))
            .collect(),
    })
}

fn read_obj(path: &Path) -> Result<TriMesh, String> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    // tobj opens the file itself; it must be a regular file of bounded size first.
    caravan::input::open_regular(path).map_err(|e| format!("cannot read: {e}"))?;
    let (models, _) =
        tobj::load_obj(path, &options).map_err(|e| format!("not a valid OBJ file: {e}"))?;
    let mut mesh = TriMesh {
        vertices: Vec::new(),
        triangles: Vec::new(),
    };
    for m in models {
        let base = mesh.vertices.len() as u32;
        mesh.vertices.extend(
            m.mesh
                .positions
                .chunks_exact(3)
                .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]),
        );
        mesh.triangles.extend(
            m.mesh
                .indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    Ok(mesh)
}
