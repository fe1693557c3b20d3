//! The extension module `pgo._pgo` of the Python package `pgo`: the pose graphs as Python classes
//! over the library's [`PoseGraph`] (planar) and [`pgo::graph3::Graph3`] (3D), and one call each
//! into the library's jobs (read, write, [`pgo::solve`] / [`pgo::solve::solve3`],
//! [`pgo::certify_estimate`] / [`pgo::solve::certify_estimate3`], [`pgo::spectrum::spectrum`] /
//! [`pgo::spectrum::spectrum3`]), chosen by the graph's dimension as the tools choose them. The
//! reports are the tools' own `--json` reports, built by the same code
//! (`pgo::cli::{solve, certify, spectrum}`) and handed to Python as JSON text; `pgo/__init__.py`
//! wraps them in classes. No orchestration here: everything a tool decides, the library decides.

use numpy::ndarray::ArrayViewD;
use numpy::{AllowTypeChange, PyArray1, PyArray2, PyArrayLikeDyn, PyArrayMethods};
use pgo::graph::{Edge, Pose2, PoseGraph, SymMat3, VertexId};
use pgo::graph3::{Edge3, Form3, Pose3, Rotation3, SymMat6};
use pgo::io::{self, AnyGraph, Dialect, Format, ReadOptions, ReadReport, WriteOptions};
use pgo::vertigo::Vertigo;
use pyo3::create_exception;
use pyo3::exceptions::{PyOSError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use std::path::{Path, PathBuf};

create_exception!(
    pgo,
    PgoError,
    PyValueError,
    "An error of pgo's library: a request it cannot carry out (e.g. two FIX poses in one \
     component, a graph too large for method=\"sdp\", an estimate of the wrong shape). A \
     ValueError."
);
create_exception!(
    pgo,
    ParseError,
    PgoError,
    "An error in an input file or text, at a place: `.path`, `.line` and `.column` (1-based, \
     columns in bytes after a UTF-8 BOM) and `.reason`; the message is the tools' error line, \
     `PATH:LINE:COL: error: REASON`."
);

/// Turns a library error into a Python exception: [`ParseError`] with its place, `OSError` (its
/// subclass by errno, e.g. `FileNotFoundError`) with the path, else [`PgoError`].
fn to_py(py: Python<'_>, e: pgo::Error) -> PyErr {
    match e {
        pgo::Error::Parse(p) => {
            let message = format!("{}: error: {}", p.location, p.kind);
            let err = ParseError::new_err(message);
            let value = err.value(py);
            let set = || -> PyResult<()> {
                value.setattr("path", &p.location.path)?;
                value.setattr("line", p.location.line)?;
                value.setattr("column", p.location.col)?;
                value.setattr("reason", p.kind.to_string())?;
                Ok(())
            };
            match set() {
                Ok(()) => err,
                Err(e) => e,
            }
        }
        pgo::Error::Io { path, source } => match source.raw_os_error() {
            // OSError(errno, strerror, filename) is FileNotFoundError, PermissionError... by errno.
            Some(code) => PyOSError::new_err((code, source.to_string(), path)),
            // No errno (the writer's errors name the path, not the temporary file): the OSError
            // subclass of the kind, e.g. FileNotFoundError for a missing directory.
            None => PyErr::from(std::io::Error::new(
                source.kind(),
                format!("{path}: {source}"),
            )),
        },
        pgo::Error::Invalid(msg) => PgoError::new_err(msg),
    }
}

fn io_to_py(py: Python<'_>, e: impl Into<pgo::Error>) -> PyErr {
    to_py(py, e.into())
}

fn invalid(msg: impl Into<String>) -> PyErr {
    PgoError::new_err(msg.into())
}

/// A value of one of the library's clap enums by its name on the command line.
fn choice<T: clap::ValueEnum>(what: &str, name: &str) -> PyResult<T> {
    T::from_str(name, false).map_err(|_| {
        let names: Vec<String> = T::value_variants()
            .iter()
            .filter_map(|v| v.to_possible_value().map(|p| format!("'{}'", p.get_name())))
            .collect();
        PyValueError::new_err(format!(
            "{what} must be one of {}, found '{name}'",
            names.join(", ")
        ))
    })
}

fn path_str(path: &Path) -> PyResult<&str> {
    path.to_str()
        .ok_or_else(|| PyValueError::new_err(format!("{}: not a UTF-8 path", path.display())))
}

/// A planar pose graph: poses with ids, relative-pose edges with information matrices, FIX ids,
/// and landmarks observed from poses when its file has them.
///
/// Read one with `pgo.read(path_or_text)`, or build one from arrays:
///
///     pgo.Graph(poses, edges, measurements, information=None, ids=None, fixed=None,
///               allow_indefinite=False)
///
/// poses: (n, 3) float (x, y, theta) per pose; edges: (m, 2) vertex ids (i, j), an edge
/// measuring the pose of j in the frame of i; measurements: (m, 3) (dx, dy, dtheta);
/// information: (m, 6) upper triangles of the information matrices in g2o order
/// (I11 I12 I13 I22 I23 I33 over x, y, theta), identity if None; ids: (n,) vertex ids of the
/// poses (0..n-1 if None), any order, distinct, 0 <= id < 2^31; fixed: vertex ids held fixed
/// (g2o's FIX). The same checks as the file reader: finite values, known ids, no self-loops,
/// positive definite information (unless allow_indefinite).
///
/// A Graph is immutable: its array attributes are copies. `with_poses` gives a graph with
/// another estimate.
#[pyclass(module = "pgo", name = "Graph", frozen)]
pub struct Graph {
    graph: PoseGraph,
    format: Format,
    dialect: Dialect,
    warnings: Vec<String>,
    vertigo: Option<Vertigo>,
    /// Where it came from: a path, "<string>" or "<arrays>".
    source: String,
}

impl Graph {
    fn from_read(graph: PoseGraph, report: ReadReport, source: String) -> Self {
        Graph {
            graph,
            format: report.format,
            dialect: report.dialect,
            warnings: report.warnings.iter().map(|w| w.to_string()).collect(),
            vertigo: report.vertigo,
            source,
        }
    }
}

/// The rows of a float array of shape (rows, cols) (any layout), or none for any empty array
/// when `rows` is None or 0; every value finite.
fn matrix(
    name: &str,
    a: &ArrayViewD<'_, f64>,
    cols: usize,
    rows: Option<usize>,
) -> PyResult<Vec<Vec<f64>>> {
    let shape = a.shape();
    if a.is_empty() && rows.unwrap_or(0) == 0 {
        return Ok(Vec::new());
    }
    if shape.len() != 2 || shape[1] != cols || rows.is_some_and(|r| r != shape[0]) {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape ({}, {cols}), found {shape:?}",
            rows.map_or("m".to_string(), |r| r.to_string())
        )));
    }
    // Logical (row-major) order whatever the strides.
    let values: Vec<f64> = a.iter().copied().collect();
    let rows: Vec<Vec<f64>> = values.chunks_exact(cols).map(|r| r.to_vec()).collect();
    for (k, row) in rows.iter().enumerate() {
        if let Some(v) = row.iter().find(|v| !v.is_finite()) {
            return Err(invalid(format!(
                "{name}[{k}]: {v} is not finite (g2o and GTSAM cannot read it back)"
            )));
        }
    }
    Ok(rows)
}

/// A vertex id from a float (arrays of ids are taken as float64 to catch fractions).
fn vertex_id(name: &str, v: f64) -> PyResult<VertexId> {
    if v.fract() != 0.0 || !(0.0..=f64::from(pgo::graph::MAX_VERTEX_ID)).contains(&v) {
        return Err(invalid(format!(
            "{name}: {v} is not a vertex id (an integer from 0 to {})",
            pgo::graph::MAX_VERTEX_ID
        )));
    }
    Ok(v as VertexId)
}

fn id_list(name: &str, a: &ArrayViewD<'_, f64>) -> PyResult<Vec<VertexId>> {
    if a.ndim() > 1 && !a.is_empty() {
        return Err(PyValueError::new_err(format!(
            "{name} must be one-dimensional, found shape {:?}",
            a.shape()
        )));
    }
    a.iter()
        .enumerate()
        .map(|(k, &v)| vertex_id(&format!("{name}[{k}]"), v))
        .collect()
}

/// The ids of n poses (`ids`, or 0..n) and the order that sorts them ascending, as the readers
/// keep poses; repeated ids refused.
fn id_order(
    n: usize,
    ids: Option<&PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
) -> PyResult<(Vec<usize>, Vec<VertexId>)> {
    let ids: Vec<VertexId> = match ids {
        Some(a) => {
            let ids = id_list("ids", &a.as_array())?;
            if ids.len() != n {
                return Err(PyValueError::new_err(format!(
                    "ids has {} entries for {n} poses",
                    ids.len()
                )));
            }
            ids
        }
        None => {
            if n > pgo::graph::MAX_VERTEX_ID as usize {
                return Err(invalid("too many poses for g2o's ids"));
            }
            (0..n as VertexId).collect()
        }
    };
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&k| ids[k]);
    for w in order.windows(2) {
        if ids[w[0]] == ids[w[1]] {
            return Err(invalid(format!("ids: vertex {} appears twice", ids[w[0]])));
        }
    }
    let sorted = order.iter().map(|&k| ids[k]).collect();
    Ok((order, sorted))
}

/// The name (`edges[k]`) and the two vertex ids of row k of an edges array; self-loops refused.
fn edge_ids(k: usize, row: &[f64]) -> PyResult<(String, VertexId, VertexId)> {
    let name = format!("edges[{k}]");
    let a = vertex_id(&name, row[0])?;
    let b = vertex_id(&name, row[1])?;
    if a == b {
        return Err(invalid(format!(
            "{name}: self-loop: edge from vertex {a} to itself"
        )));
    }
    Ok((name, a, b))
}

/// Row k's information matrix refused unless its Cholesky factorization succeeded (`check`: the
/// failing pivot), as the readers refuse it without --allow-indefinite.
fn definite(k: usize, check: Result<(), usize>) -> PyResult<()> {
    check.map_err(|pivot| {
        invalid(format!(
            "information[{k}]: the information matrix is not positive definite (pivot {pivot} of its Cholesky factorization is not positive); pass allow_indefinite=True to accept it"
        ))
    })
}

/// The dense index of vertex `id` among the poses' sorted ids, for the error message of `name`.
fn pose_index(sorted_ids: &[VertexId], name: &str, id: VertexId) -> PyResult<usize> {
    sorted_ids
        .binary_search(&id)
        .map_err(|_| invalid(format!("{name}: vertex {id} is not one of the poses' ids")))
}

/// The dense indices of the `fixed` ids, in their order, without repeats.
fn fixed_indices(
    sorted_ids: &[VertexId],
    fixed: Option<&PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
) -> PyResult<Vec<usize>> {
    let mut indices = Vec::new();
    if let Some(f) = fixed {
        for (k, id) in id_list("fixed", &f.as_array())?.into_iter().enumerate() {
            let i = pose_index(sorted_ids, &format!("fixed[{k}]"), id)?;
            if !indices.contains(&i) {
                indices.push(i);
            }
        }
    }
    Ok(indices)
}

fn float_array<'py>(
    py: Python<'py>,
    v: Vec<f64>,
    cols: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let rows = v.len() / cols;
    PyArray1::from_vec(py, v).reshape([rows, cols])
}

fn id_array<'py>(py: Python<'py>, v: Vec<i64>, cols: usize) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let rows = v.len() / cols;
    PyArray1::from_vec(py, v).reshape([rows, cols])
}

#[pymethods]
impl Graph {
    #[new]
    #[pyo3(signature = (poses, edges, measurements, information=None, ids=None, fixed=None, *, allow_indefinite=false))]
    fn new(
        poses: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        edges: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        measurements: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        information: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
        ids: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
        fixed: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
        allow_indefinite: bool,
    ) -> PyResult<Self> {
        let poses_view = poses.as_array();
        let pose_rows = matrix("poses", &poses_view, 3, None)?;
        // Poses in ascending id order, as the reader keeps them.
        let (order, sorted_ids) = id_order(pose_rows.len(), ids.as_ref())?;
        let sorted_poses: Vec<Pose2> = order
            .iter()
            .map(|&k| Pose2::new(pose_rows[k][0], pose_rows[k][1], pose_rows[k][2]))
            .collect();
        let index = |name: &str, id: VertexId| pose_index(&sorted_ids, name, id);

        let edges_view = edges.as_array();
        let edge_rows = matrix("edges", &edges_view, 2, None)?;
        let m = edge_rows.len();
        let measurements_view = measurements.as_array();
        let measurement_rows = matrix("measurements", &measurements_view, 3, Some(m))?;
        let information_rows = information
            .as_ref()
            .map(|a| matrix("information", &a.as_array(), 6, Some(m)))
            .transpose()?;
        let mut graph_edges = Vec::with_capacity(m);
        for k in 0..m {
            let (name, a, b) = edge_ids(k, &edge_rows[k])?;
            let noise = match &information_rows {
                Some(rows) => {
                    let r = &rows[k];
                    SymMat3([r[0], r[1], r[2], r[3], r[4], r[5]])
                }
                None => SymMat3::IDENTITY,
            };
            if !allow_indefinite {
                definite(k, noise.check_positive_definite())?;
            }
            let z = &measurement_rows[k];
            graph_edges.push(Edge {
                i: index(&name, a)?,
                j: index(&name, b)?,
                measurement: Pose2::new(z[0], z[1], z[2]),
                noise,
            });
        }
        let mut graph = PoseGraph::with_edges(sorted_poses, graph_edges);
        graph.fixed = fixed_indices(&sorted_ids, fixed.as_ref())?;
        graph.ids = sorted_ids;
        Ok(Graph {
            graph,
            format: Format::G2o,
            dialect: Dialect::G2o,
            warnings: Vec::new(),
            vertigo: None,
            source: "<arrays>".into(),
        })
    }

    /// The estimate: (n, 3) float64, one row (x, y, theta) per pose, in ascending id order.
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let v = self.graph.poses.iter().flat_map(|p| p.values()).collect();
        float_array(py, v, 3)
    }

    /// The poses' vertex ids: (n,) int64, ascending.
    #[getter]
    fn ids<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        PyArray1::from_vec(py, self.graph.ids.iter().map(|&i| i64::from(i)).collect())
    }

    /// The edges as vertex ids: (m, 2) int64 (i, j) in file order; an edge measures the pose of
    /// j in the frame of i.
    #[getter]
    fn edges<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let ids = &self.graph.ids;
        let v = self
            .graph
            .edges
            .iter()
            .flat_map(|e| [i64::from(ids[e.i]), i64::from(ids[e.j])])
            .collect();
        id_array(py, v, 2)
    }

    /// The edges as row indices into `poses`: (m, 2) int64.
    #[getter]
    fn edge_indices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let v = self
            .graph
            .edges
            .iter()
            .flat_map(|e| [e.i as i64, e.j as i64])
            .collect();
        id_array(py, v, 2)
    }

    /// The measurements: (m, 3) float64 (dx, dy, dtheta), the pose of j in the frame of i.
    #[getter]
    fn measurements<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let v = self
            .graph
            .edges
            .iter()
            .flat_map(|e| e.measurement.values())
            .collect();
        float_array(py, v, 3)
    }

    /// The information matrices: (m, 6) float64, upper triangles in g2o order
    /// (I11 I12 I13 I22 I23 I33 over x, y, theta), whatever the file's dialect (TORO's order
    /// is reordered, covariances are inverted; a singular covariance gives a row of NaN).
    #[getter]
    fn information<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let v = self
            .graph
            .edges
            .iter()
            .flat_map(|e| self.graph.information(e).map_or([f64::NAN; 6], |m| m.0))
            .collect();
        float_array(py, v, 6)
    }

    /// The fixed poses' ids (g2o's FIX), in the order of the FIX lines: (k,) int64.
    #[getter]
    fn fixed<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let ids = &self.graph.ids;
        PyArray1::from_vec(
            py,
            self.graph
                .fixed
                .iter()
                .map(|&k| i64::from(ids[k]))
                .collect(),
        )
    }

    /// The landmarks' ids: (L,) int64, ascending (empty for a pose graph).
    #[getter]
    fn landmark_ids<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let ids = &self.graph.landmarks.ids;
        PyArray1::from_vec(py, ids.iter().map(|&i| i64::from(i)).collect())
    }

    /// The landmarks' positions: (L, 2) float64 (x, y), in the order of `landmark_ids`.
    #[getter]
    fn landmarks<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let v = self
            .graph
            .landmarks
            .positions
            .iter()
            .flatten()
            .copied()
            .collect();
        float_array(py, v, 2)
    }

    /// The landmark observations: (o, 2) int64 (pose id, landmark id), in file order.
    #[getter]
    fn observations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let marks = &self.graph.landmarks;
        let v = marks
            .observations
            .iter()
            .flat_map(|o| {
                [
                    i64::from(self.graph.ids[o.pose]),
                    i64::from(marks.ids[o.landmark]),
                ]
            })
            .collect();
        id_array(py, v, 2)
    }

    /// The observations' measurements: (o, 2) float64 (dx, dy), the landmark in the pose's
    /// frame.
    #[getter]
    fn observation_measurements<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let obs = &self.graph.landmarks.observations;
        float_array(py, obs.iter().flat_map(|o| o.d).collect(), 2)
    }

    /// The observations' information matrices: (o, 3) float64 (I11 I12 I22).
    #[getter]
    fn observation_information<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let obs = &self.graph.landmarks.observations;
        float_array(py, obs.iter().flat_map(|o| o.information.0).collect(), 3)
    }

    /// 2: a planar graph (`pgo.Graph3` is 3D).
    #[getter]
    fn dimension(&self) -> u8 {
        2
    }

    /// Number of poses.
    #[getter]
    fn num_poses(&self) -> usize {
        self.graph.num_poses()
    }

    /// Number of edges.
    #[getter]
    fn num_edges(&self) -> usize {
        self.graph.edges.len()
    }

    /// The file format it was read in ("g2o" or "toro"; "g2o" for a graph built from arrays).
    #[getter]
    fn format(&self) -> &'static str {
        self.format.name()
    }

    /// How the file's noise values were read: "g2o", "toro-info", "toro-cov" or "g2o-cov".
    #[getter]
    fn dialect(&self) -> &'static str {
        self.dialect.name()
    }

    /// Whether the poses came from vertex lines (else they were composed along a spanning tree
    /// of the edges).
    #[getter]
    fn has_vertices(&self) -> bool {
        self.graph.vertices_declared
    }

    /// The reader's warnings (`PATH:LINE:COL: warning: ...`, e.g. skipped unknown tags).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// Where the graph came from: its path, "<string>" for text, "<arrays>".
    #[getter]
    fn source(&self) -> &str {
        &self.source
    }

    /// This graph with another estimate: `poses` (n, 3) in the order of `ids`, and `landmarks`
    /// (L, 2) if given (else the graph's). What `pgo-solve -o` writes is
    /// `graph.with_poses(solution.poses, solution.landmarks)`.
    #[pyo3(signature = (poses, landmarks=None))]
    fn with_poses(
        &self,
        poses: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        landmarks: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
    ) -> PyResult<Self> {
        let mut graph = self.graph.clone();
        let view = poses.as_array();
        let rows = matrix("poses", &view, 3, Some(graph.num_poses()))?;
        graph.poses = rows.iter().map(|r| Pose2::new(r[0], r[1], r[2])).collect();
        graph.vertices_declared = true;
        if let Some(l) = &landmarks {
            let view = l.as_array();
            let rows = matrix("landmarks", &view, 2, Some(graph.landmarks.len()))?;
            graph.landmarks.positions = rows.iter().map(|r| [r[0], r[1]]).collect();
            graph.landmarks.declared = true;
        }
        Ok(Graph {
            graph,
            format: self.format,
            dialect: self.dialect,
            warnings: self.warnings.clone(),
            vertigo: self.vertigo.clone(),
            source: self.source.clone(),
        })
    }

    /// Writes the graph to `path` as pgo-convert does: `format` "g2o" or "toro" (default: from
    /// the extension, .g2o or .graph, else the format it was read in), `dialect` the order and
    /// kind of the noise values (default: the format's own, information matrices); vertices
    /// sorted by id, edges in input order, FIX last, shortest round-trip numbers. Atomic: a
    /// temporary file in the same directory renamed over `path` when complete.
    #[pyo3(signature = (path, format=None, dialect=None))]
    fn write(
        &self,
        py: Python<'_>,
        path: PathBuf,
        format: Option<&str>,
        dialect: Option<&str>,
    ) -> PyResult<()> {
        let path = path_str(&path)?;
        if path == "-" {
            return Err(invalid(
                "write: give a file path (to_text() returns the file's text)",
            ));
        }
        let format = match format {
            Some(f) => choice::<Format>("format", f)?,
            None => Format::from_extension(path).unwrap_or(self.format),
        };
        let dialect = match dialect {
            Some(d) => choice::<Dialect>("dialect", d)?,
            None => format.default_dialect(),
        };
        self.write_to(py, path, format, dialect)
    }

    /// The graph as the text of a file in `format` ("g2o" by default if built from arrays, else
    /// the format it was read in) and `dialect`, exactly the bytes `write` writes.
    #[pyo3(signature = (format=None, dialect=None))]
    fn to_text(
        &self,
        py: Python<'_>,
        format: Option<&str>,
        dialect: Option<&str>,
    ) -> PyResult<String> {
        let format = match format {
            Some(f) => choice::<Format>("format", f)?,
            None => self.format,
        };
        let dialect = match dialect {
            Some(d) => choice::<Dialect>("dialect", d)?,
            None => format.default_dialect(),
        };
        let dir = tempfile::tempdir()
            .map_err(|e| to_py(py, pgo::Error::io("a temporary directory", e)))?;
        let file = dir.path().join("graph");
        let path = path_str(&file)?.to_string();
        self.write_to(py, &path, format, dialect)?;
        std::fs::read_to_string(&file).map_err(|e| to_py(py, pgo::Error::io(&path, e)))
    }

    fn __repr__(&self) -> String {
        let g = &self.graph;
        format!(
            "<pgo.Graph: {} poses, {} edges{}{}, {} (dialect {}), from {}>",
            g.num_poses(),
            g.edges.len(),
            if g.landmarks.is_empty() {
                String::new()
            } else {
                format!(
                    ", {} landmarks, {} observations",
                    g.landmarks.len(),
                    g.landmarks.observations.len()
                )
            },
            if g.fixed.is_empty() {
                String::new()
            } else {
                format!(", {} fixed", g.fixed.len())
            },
            self.format.name(),
            self.dialect.name(),
            self.source
        )
    }

    /// Whether two graphs hold the same poses, ids, edges, noise values (of the same kind),
    /// fixed poses and landmarks (format, dialect, warnings and source aside).
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        match other.cast::<Graph>() {
            Ok(o) => {
                let o = o.get();
                self.graph == o.graph && self.vertigo == o.vertigo
            }
            Err(_) => false,
        }
    }
}

impl Graph {
    fn write_to(
        &self,
        py: Python<'_>,
        path: &str,
        format: Format,
        dialect: Dialect,
    ) -> PyResult<()> {
        if dialect.toro_order() != (format == Format::Toro) {
            return Err(invalid(format!(
                "dialect {dialect} does not fit {format} output (g2o files take g2o or g2o-cov, TORO files toro-info or toro-cov)"
            )));
        }
        let mut graph = self.graph.clone();
        graph.convert_noise(dialect.noise()).map_err(|k| {
            invalid(format!(
                "edge {} -> {} has a singular noise matrix that cannot be inverted for dialect {dialect}",
                graph.ids[graph.edges[k].i], graph.ids[graph.edges[k].j]
            ))
        })?;
        let vertigo = self.vertigo.as_ref();
        py.detach(|| io::write_path_with(&graph, vertigo, WriteOptions { format, dialect }, path))
            .map_err(|e| io_to_py(py, e))
    }
}

/// The number of values of a pose (and of a measurement) in a 3D graph's form: x y z qx qy qz qw
/// (g2o) or x y z roll pitch yaw (TORO).
fn pose_width(form: Form3) -> usize {
    match form {
        Form3::G2o => 7,
        Form3::Toro => 6,
    }
}

/// 3D poses from the rows of an (n, 7) or (n, 6) array in the graph's form, with the reader's
/// check on quaternions (one that cannot be normalized is refused).
fn poses3(name: &str, a: &ArrayViewD<'_, f64>, form: Form3, n: usize) -> PyResult<Vec<Pose3>> {
    let rows = matrix(name, a, pose_width(form), Some(n))?;
    rows.iter()
        .enumerate()
        .map(|(k, r)| {
            let rotation = match form {
                Form3::G2o => {
                    let q = [r[3], r[4], r[5], r[6]];
                    let norm2: f64 = q.iter().map(|x| x * x).sum();
                    if !(norm2 > 0.0 && norm2.is_finite()) {
                        return Err(invalid(format!(
                            "{name}[{k}]: the quaternion ({:?}, {:?}, {:?}, {:?}) cannot be normalized",
                            q[0], q[1], q[2], q[3]
                        )));
                    }
                    Rotation3::Quaternion(q)
                }
                Form3::Toro => Rotation3::Euler([r[3], r[4], r[5]]),
            };
            Ok(Pose3 {
                translation: [r[0], r[1], r[2]],
                rotation,
            })
        })
        .collect()
}

/// A 3D pose graph (g2o `VERTEX_SE3:QUAT`/`EDGE_SE3:QUAT` or TORO `VERTEX3`/`EDGE3`): poses in
/// SE(3) with ids, relative-pose edges with 6x6 information matrices, FIX ids; `pgo.read`
/// returns one for a 3D file. Every value is kept as read and written back bit for bit.
///
/// The rotations are in the file's form (`format`): g2o quaternions, a pose or measurement row
/// being `x y z qx qy qz qw` (7 columns, Hamilton, w last, not necessarily of unit norm: the
/// rotation is q/|q|), or TORO Euler angles, `x y z roll pitch yaw` (6 columns). The information
/// matrices are (m, 21) upper triangles row by row over the file's coordinates (x y z qx qy qz,
/// or x y z roll pitch yaw). The two forms are not converted into each other (not lossless).
///
/// A Graph3 is immutable: its array attributes are copies. `with_poses` gives a graph with
/// another estimate.
///
/// `Graph3(poses, edges, measurements, information=None, ids=None, fixed=None, *, form="g2o",
/// allow_indefinite=False)` builds one from arrays, as `Graph` does in 2D: poses (n, 7) or
/// (n, 6) in `form`'s coordinates ("g2o": quaternions, "toro": Euler angles), edges (m, 2) of
/// vertex ids, measurements as poses, information (m, 21) upper triangles (default: identity),
/// ids (n,) (default 0..n-1), fixed ids; every information matrix must be positive definite
/// unless `allow_indefinite`. It writes as a file of its form (g2o `.g2o`, TORO `.graph`).
#[pyclass(module = "pgo", name = "Graph3", frozen)]
pub struct Graph3 {
    graph: pgo::graph3::Graph3,
    format: Format,
    dialect: Dialect,
    warnings: Vec<String>,
    /// Where it came from: a path or "<string>".
    source: String,
}

impl Graph3 {
    fn from_read(graph: pgo::graph3::Graph3, report: ReadReport, source: String) -> Self {
        Graph3 {
            graph,
            format: report.format,
            dialect: report.dialect,
            warnings: report.warnings.iter().map(|w| w.to_string()).collect(),
            source,
        }
    }

    fn width(&self) -> usize {
        pose_width(self.graph.form)
    }

    /// The format and dialect of an output: `format` (else the extension of `path`, else the
    /// format it was read in) and `dialect`, which must be the format's own (pgo-convert's
    /// check).
    fn output(
        &self,
        path: Option<&str>,
        format: Option<&str>,
        dialect: Option<&str>,
    ) -> PyResult<(Format, Dialect)> {
        let format = match format {
            Some(f) => choice::<Format>("format", f)?,
            None => path.and_then(Format::from_extension).unwrap_or(self.format),
        };
        let requested = dialect
            .map(|d| choice::<Dialect>("dialect", d))
            .transpose()?;
        let dialect =
            pgo::cli::convert::dialect3(format, requested, "dialect").map_err(invalid_of)?;
        Ok((format, dialect))
    }
}

/// A library error that carries no place or path, as a [`PgoError`].
fn invalid_of(e: pgo::Error) -> PyErr {
    PgoError::new_err(e.to_string())
}

#[pymethods]
impl Graph3 {
    #[new]
    #[pyo3(signature = (poses, edges, measurements, information=None, ids=None, fixed=None, *, form="g2o", allow_indefinite=false))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        poses: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        edges: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        measurements: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        information: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
        ids: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
        fixed: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
        form: &str,
        allow_indefinite: bool,
    ) -> PyResult<Self> {
        let (form, format) = match form {
            "g2o" => (Form3::G2o, Format::G2o),
            "toro" => (Form3::Toro, Format::Toro),
            other => {
                return Err(invalid(format!(
                    "form must be \"g2o\" (quaternions) or \"toro\" (Euler angles), found {other:?}"
                )));
            }
        };
        let poses_view = poses.as_array();
        let n = poses_view.shape().first().copied().unwrap_or(0);
        let rows = poses3("poses", &poses_view, form, n)?;
        let (order, sorted_ids) = id_order(rows.len(), ids.as_ref())?;
        let sorted_poses: Vec<Pose3> = order.iter().map(|&k| rows[k]).collect();

        let edges_view = edges.as_array();
        let edge_rows = matrix("edges", &edges_view, 2, None)?;
        let m = edge_rows.len();
        let measurements = poses3("measurements", &measurements.as_array(), form, m)?;
        let information_rows = information
            .as_ref()
            .map(|a| matrix("information", &a.as_array(), 21, Some(m)))
            .transpose()?;
        let mut graph_edges = Vec::with_capacity(m);
        for k in 0..m {
            let (name, a, b) = edge_ids(k, &edge_rows[k])?;
            let information = match &information_rows {
                Some(rows) => SymMat6(rows[k].as_slice().try_into().expect("21 columns checked")),
                None => SymMat6::IDENTITY,
            };
            if !allow_indefinite {
                definite(k, information.check_positive_definite())?;
            }
            graph_edges.push(Edge3 {
                i: pose_index(&sorted_ids, &name, a)?,
                j: pose_index(&sorted_ids, &name, b)?,
                measurement: measurements[k],
                information,
            });
        }
        let graph = pgo::graph3::Graph3 {
            fixed: fixed_indices(&sorted_ids, fixed.as_ref())?,
            ids: sorted_ids,
            poses: sorted_poses,
            edges: graph_edges,
            form,
        };
        Ok(Graph3 {
            graph,
            format,
            dialect: format.default_dialect(),
            warnings: Vec::new(),
            source: "<arrays>".into(),
        })
    }

    /// The estimate: (n, 7) float64 `x y z qx qy qz qw` per pose for a g2o graph, (n, 6)
    /// `x y z roll pitch yaw` for a TORO one, exactly as read, in ascending id order.
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let v = self.graph.poses.iter().flat_map(|p| p.values()).collect();
        float_array(py, v, self.width())
    }

    /// The poses' vertex ids: (n,) int64, ascending.
    #[getter]
    fn ids<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        PyArray1::from_vec(py, self.graph.ids.iter().map(|&i| i64::from(i)).collect())
    }

    /// The edges as vertex ids: (m, 2) int64 (i, j) in file order; an edge measures the pose of
    /// j in the frame of i.
    #[getter]
    fn edges<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let ids = &self.graph.ids;
        let v = self
            .graph
            .edges
            .iter()
            .flat_map(|e| [i64::from(ids[e.i]), i64::from(ids[e.j])])
            .collect();
        id_array(py, v, 2)
    }

    /// The edges as row indices into `poses`: (m, 2) int64.
    #[getter]
    fn edge_indices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let v = self
            .graph
            .edges
            .iter()
            .flat_map(|e| [e.i as i64, e.j as i64])
            .collect();
        id_array(py, v, 2)
    }

    /// The measurements: (m, 7) float64 `x y z qx qy qz qw` (g2o) or (m, 6)
    /// `x y z roll pitch yaw` (TORO), the pose of j in the frame of i, exactly as read.
    #[getter]
    fn measurements<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let v = self
            .graph
            .edges
            .iter()
            .flat_map(|e| e.measurement.values())
            .collect();
        float_array(py, v, self.width())
    }

    /// The information matrices: (m, 21) float64, the upper triangle row by row as the file
    /// holds it (I11 I12 ... I16 I22 ... I66), over x y z qx qy qz (g2o) or x y z roll pitch
    /// yaw (TORO).
    #[getter]
    fn information<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let v = self
            .graph
            .edges
            .iter()
            .flat_map(|e| e.information.0)
            .collect();
        float_array(py, v, 21)
    }

    /// The fixed poses' ids (FIX lines), in the order of the FIX lines: (k,) int64.
    #[getter]
    fn fixed<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let ids = &self.graph.ids;
        PyArray1::from_vec(
            py,
            self.graph
                .fixed
                .iter()
                .map(|&k| i64::from(ids[k]))
                .collect(),
        )
    }

    /// 3: a 3D graph (`pgo.Graph` is planar).
    #[getter]
    fn dimension(&self) -> u8 {
        3
    }

    /// Number of poses.
    #[getter]
    fn num_poses(&self) -> usize {
        self.graph.num_poses()
    }

    /// Number of edges.
    #[getter]
    fn num_edges(&self) -> usize {
        self.graph.edges.len()
    }

    /// The file format it was read in, which is also the form of its rotations: "g2o"
    /// (quaternions) or "toro" (Euler angles).
    #[getter]
    fn format(&self) -> &'static str {
        self.format.name()
    }

    /// How the file's noise values were read: "g2o" or "toro-info" (3D files hold information
    /// matrices).
    #[getter]
    fn dialect(&self) -> &'static str {
        self.dialect.name()
    }

    /// The reader's warnings (`PATH:LINE:COL: warning: ...`, e.g. skipped unknown tags).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// Where the graph came from: its path, or "<string>" for text.
    #[getter]
    fn source(&self) -> &str {
        &self.source
    }

    /// This graph with another estimate: `poses` (n, 7) for a g2o graph or (n, 6) for a TORO
    /// one, in the order of `ids` (quaternions that cannot be normalized are refused). What
    /// `pgo-solve -o` writes is `graph.with_poses(solution.poses)`.
    fn with_poses(&self, poses: PyArrayLikeDyn<'_, f64, AllowTypeChange>) -> PyResult<Self> {
        let mut graph = self.graph.clone();
        graph.poses = poses3("poses", &poses.as_array(), graph.form, graph.num_poses())?;
        Ok(Graph3 {
            graph,
            format: self.format,
            dialect: self.dialect,
            warnings: self.warnings.clone(),
            source: self.source.clone(),
        })
    }

    /// Writes the graph to `path` as pgo-convert does: in its own form only (`format` "g2o" for
    /// a g2o graph, "toro" for a TORO one; default: from the extension, .g2o or .graph, else the
    /// format it was read in; the other form is refused with pgo-convert's message), `dialect`
    /// the format's own (information matrices); vertices sorted by id, edges in input order,
    /// FIX last, shortest round-trip numbers: every value read back bit for bit. Atomic: a
    /// temporary file in the same directory renamed over `path` when complete.
    #[pyo3(signature = (path, format=None, dialect=None))]
    fn write(
        &self,
        py: Python<'_>,
        path: PathBuf,
        format: Option<&str>,
        dialect: Option<&str>,
    ) -> PyResult<()> {
        let path = path_str(&path)?;
        if path == "-" {
            return Err(invalid(
                "write: give a file path (to_text() returns the file's text)",
            ));
        }
        let (format, _) = self.output(Some(path), format, dialect)?;
        let graph = &self.graph;
        py.detach(|| io::write3_path(graph, format, path))
            .map_err(|e| io_to_py(py, e))
    }

    /// The graph as the text of a file in `format` (default: the format it was read in) and
    /// `dialect`, exactly the bytes `write` writes.
    #[pyo3(signature = (format=None, dialect=None))]
    fn to_text(
        &self,
        py: Python<'_>,
        format: Option<&str>,
        dialect: Option<&str>,
    ) -> PyResult<String> {
        let (format, _) = self.output(None, format, dialect)?;
        let mut bytes = Vec::new();
        io::write3(&self.graph, format, &mut bytes).map_err(|e| io_to_py(py, e))?;
        String::from_utf8(bytes).map_err(|e| invalid(e.to_string()))
    }

    fn __repr__(&self) -> String {
        let g = &self.graph;
        format!(
            "<pgo.Graph3: {} poses, {} edges, 3D{}, {} (dialect {}), from {}>",
            g.num_poses(),
            g.edges.len(),
            if g.fixed.is_empty() {
                String::new()
            } else {
                format!(", {} fixed", g.fixed.len())
            },
            self.format.name(),
            self.dialect.name(),
            self.source
        )
    }

    /// Whether two 3D graphs hold the same poses, ids, edges, information matrices and fixed
    /// poses, in the same form (format, dialect, warnings and source aside).
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        match other.cast::<Graph3>() {
            Ok(o) => self.graph == o.get().graph,
            Err(_) => false,
        }
    }
}

fn read_options(
    format: Option<&str>,
    dialect: Option<&str>,
    strict: bool,
    ignore_equiv: bool,
    allow_indefinite: bool,
) -> PyResult<ReadOptions> {
    Ok(ReadOptions {
        format: format.map(|f| choice::<Format>("format", f)).transpose()?,
        dialect: dialect
            .map(|d| choice::<Dialect>("dialect", d))
            .transpose()?,
        strict,
        ignore_equiv,
        allow_indefinite,
    })
}

/// A graph read from a file, planar or 3D, as the Python object of its class.
fn graph_object(
    py: Python<'_>,
    graph: AnyGraph,
    report: ReadReport,
    source: String,
) -> PyResult<Py<PyAny>> {
    Ok(match graph {
        AnyGraph::Planar(g) => Bound::new(py, Graph::from_read(g, report, source))?
            .into_any()
            .unbind(),
        AnyGraph::Spatial(g) => Bound::new(py, Graph3::from_read(g, report, source))?
            .into_any()
            .unbind(),
    })
}

/// Reads the graph file at `path` (pgo.read's path branch): a `Graph`, or a `Graph3` for a 3D
/// file, as the tools read them.
#[pyfunction]
#[pyo3(signature = (path, format=None, dialect=None, strict=false, ignore_equiv=false, allow_indefinite=false))]
fn read_path(
    py: Python<'_>,
    path: PathBuf,
    format: Option<&str>,
    dialect: Option<&str>,
    strict: bool,
    ignore_equiv: bool,
    allow_indefinite: bool,
) -> PyResult<Py<PyAny>> {
    let options = read_options(format, dialect, strict, ignore_equiv, allow_indefinite)?;
    let path = path_str(&path)?;
    if path == "-" {
        return Err(invalid("read: give a path or the text of a file, not '-'"));
    }
    let (graph, report) = py
        .detach(|| io::read_any_path(path, &options))
        .map_err(|e| io_to_py(py, e))?;
    graph_object(py, graph, report, path.to_string())
}

/// Reads a graph from the bytes of a file (pgo.read's text branch): a `Graph`, or a `Graph3`
/// for a 3D file; `name` is the path its errors name.
#[pyfunction]
#[pyo3(signature = (data, name="<string>", format=None, dialect=None, strict=false, ignore_equiv=false, allow_indefinite=false))]
#[allow(clippy::too_many_arguments)]
fn read_bytes(
    py: Python<'_>,
    data: &[u8],
    name: &str,
    format: Option<&str>,
    dialect: Option<&str>,
    strict: bool,
    ignore_equiv: bool,
    allow_indefinite: bool,
) -> PyResult<Py<PyAny>> {
    let options = read_options(format, dialect, strict, ignore_equiv, allow_indefinite)?;
    let (graph, report) = py
        .detach(|| io::read_any(data, name, &options))
        .map_err(|e| io_to_py(py, e))?;
    graph_object(py, graph, report, name.to_string())
}

fn check_tolerance(tol: f64) -> PyResult<()> {
    if tol.is_finite() && tol >= 0.0 {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "tol must be a finite number >= 0, found {tol}"
        )))
    }
}

/// The graph a job is asked of: a planar `Graph` or a 3D `Graph3`.
enum AnyRef<'a> {
    Planar(&'a Graph),
    Spatial(&'a Graph3),
}

fn any_graph<'a>(graph: &'a Bound<'_, PyAny>) -> PyResult<AnyRef<'a>> {
    if let Ok(g) = graph.cast::<Graph>() {
        Ok(AnyRef::Planar(g.get()))
    } else if let Ok(g) = graph.cast::<Graph3>() {
        Ok(AnyRef::Spatial(g.get()))
    } else {
        Err(PyTypeError::new_err(format!(
            "expected a pgo.Graph or a pgo.Graph3, found {}",
            graph.get_type().name()?
        )))
    }
}

/// Solves the graph (pgo.solve): the `pgo-solve --json --no-timings` report as JSON text, the
/// estimate ((n, 3) planar; (n, 7) or (n, 6) 3D, in the graph's form) and the landmark positions
/// ((L, 2); (0, 3) for a 3D graph). 3D graphs are solved by [`pgo::solve::solve3`], which refuses
/// what does not apply to them (method "sdp", refine on a TORO file); `solver` is then not used.
#[pyfunction]
#[pyo3(signature = (graph, weights="isotropic", tol=1e-6, method="auto", solver=None, max_rank=6, staircase_budget=50.0, refine=false))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn solve<'py>(
    py: Python<'py>,
    graph: &Bound<'py, PyAny>,
    weights: &str,
    tol: f64,
    method: &str,
    solver: Option<&str>,
    max_rank: usize,
    staircase_budget: f64,
    refine: bool,
) -> PyResult<(String, Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>)> {
    check_tolerance(tol)?;
    if !(1..=64).contains(&max_rank) {
        return Err(PyValueError::new_err(format!(
            "max_rank must be from 1 to 64, found {max_rank}"
        )));
    }
    if !(staircase_budget.is_finite() && staircase_budget >= 0.0) {
        return Err(PyValueError::new_err(format!(
            "staircase_budget must be a finite number >= 0, found {staircase_budget}"
        )));
    }
    let options = pgo::SolveOptions {
        method: choice("method", method)?,
        solver: choice("solver", solver.unwrap_or("ipm"))?,
        weights: choice("weights", weights)?,
        tolerance: tol,
        refine,
        max_rank,
        staircase_budget: staircase_budget * 1e9,
        ..Default::default()
    };
    let g = match any_graph(graph)? {
        AnyRef::Planar(g) => g,
        AnyRef::Spatial(g) => {
            let solution = py
                .detach(|| pgo::solve::solve3(&g.graph, &options))
                .map_err(|e| to_py(py, e))?;
            let report = pgo::cli::solve::Report3::new(&solution, g.warnings.clone(), None);
            let json = pgo::cli::common::to_json_line(&report).map_err(|e| to_py(py, e))?;
            let poses = solution.estimate.iter().flat_map(|p| p.values()).collect();
            return Ok((
                json,
                float_array(py, poses, g.width())?,
                float_array(py, Vec::new(), 3)?,
            ));
        }
    };
    let solution = py
        .detach(|| pgo::solve(&g.graph, &options))
        .map_err(|e| to_py(py, e))?;
    let mut report = pgo::cli::solve::Report::new(&solution, None, g.warnings.clone(), None);
    report
        .note_suspect_loop_closures(&g.graph, options.weights)
        .map_err(|e| to_py(py, e))?;
    let json = pgo::cli::common::to_json_line(&report).map_err(|e| to_py(py, e))?;
    let poses = solution.estimate.iter().flat_map(|p| p.values()).collect();
    let landmarks = solution
        .landmark_estimate
        .iter()
        .flatten()
        .copied()
        .collect();
    Ok((
        json,
        float_array(py, poses, 3)?,
        float_array(py, landmarks, 2)?,
    ))
}

/// Certifies an estimate (pgo.certify): the `pgo-certify --json` report as JSON text. For a 3D
/// graph, `poses` is (n, 7) or (n, 6) in the graph's form (None: the file's own poses) and
/// [`pgo::solve::certify_estimate3`] certifies it.
#[pyfunction]
#[pyo3(signature = (graph, poses=None, landmarks=None, weights="isotropic", tol=1e-6))]
fn certify(
    py: Python<'_>,
    graph: &Bound<'_, PyAny>,
    poses: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
    landmarks: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
    weights: &str,
    tol: f64,
) -> PyResult<String> {
    check_tolerance(tol)?;
    let options = pgo::solve::CertifyOptions {
        weights: choice("weights", weights)?,
        tolerance: tol,
    };
    let g = match any_graph(graph)? {
        AnyRef::Planar(g) => g,
        AnyRef::Spatial(g) => {
            if landmarks.is_some() {
                return Err(invalid(
                    "landmarks: a 3D graph has no landmarks (pass poses only)",
                ));
            }
            let (estimate, source) = match &poses {
                None => (g.graph.poses.clone(), g.source.as_str()),
                Some(p) => (
                    poses3("poses", &p.as_array(), g.graph.form, g.graph.num_poses())?,
                    "<poses>",
                ),
            };
            let report = py
                .detach(|| pgo::solve::certify_estimate3(&g.graph, &estimate, &options, source))
                .map_err(|e| to_py(py, e))?;
            let json = pgo::cli::certify::JsonReport {
                report: &report,
                warnings: g.warnings.clone(),
            };
            return pgo::cli::common::to_json_line(&json).map_err(|e| to_py(py, e));
        }
    };
    let n = g.graph.num_poses();
    let marks = &g.graph.landmarks;
    let mut estimate: Vec<Pose2> = match &poses {
        None => {
            if !g.graph.vertices_declared {
                return Err(invalid(format!(
                    "{}: the file has no vertex lines, so there is no estimate to certify (pass poses)",
                    g.source
                )));
            }
            g.graph.poses.clone()
        }
        Some(p) => {
            let view = p.as_array();
            let rows = matrix("poses", &view, 3, Some(n))?;
            rows.iter().map(|r| Pose2::new(r[0], r[1], r[2])).collect()
        }
    };
    let positions: Vec<[f64; 2]> = match &landmarks {
        None if marks.is_empty() => Vec::new(),
        None if poses.is_none() && marks.declared => marks.positions.clone(),
        None => {
            return Err(invalid(format!(
                "the graph has {} landmarks: pass their positions as landmarks, shape ({}, 2)",
                marks.len(),
                marks.len()
            )));
        }
        Some(l) => {
            let view = l.as_array();
            let rows = matrix("landmarks", &view, 2, Some(marks.len()))?;
            rows.iter().map(|r| [r[0], r[1]]).collect()
        }
    };
    estimate.extend(positions.iter().map(|&[x, y]| Pose2::new(x, y, 0.0)));
    let source = if poses.is_some() {
        "<poses>"
    } else {
        g.source.as_str()
    };
    let report = py
        .detach(|| pgo::certify_estimate(&g.graph, &estimate, &options, source))
        .map_err(|e| to_py(py, e))?;
    let json = pgo::cli::certify::JsonReport {
        report: &report,
        warnings: g.warnings.clone(),
    };
    pgo::cli::common::to_json_line(&json).map_err(|e| to_py(py, e))
}

/// The graph's spectra (pgo.spectrum): the `pgo-spectrum --json` report as JSON text, and the
/// first ids of the components whose eigenvalue iteration did not converge (pgo-spectrum's
/// warnings). A 3D graph's are [`pgo::spectrum::spectrum3`]'s (`solver` not used).
#[pyfunction]
#[pyo3(signature = (graph, k=0, weights="isotropic", solver="ipm"))]
fn spectrum(
    py: Python<'_>,
    graph: &Bound<'_, PyAny>,
    k: usize,
    weights: &str,
    solver: &str,
) -> PyResult<(String, Vec<u32>)> {
    let options = pgo::spectrum::SpectrumOptions {
        weights: choice("weights", weights)?,
        count: k,
        solver: choice("solver", solver)?,
    };
    let g = match any_graph(graph)? {
        AnyRef::Planar(g) => g,
        AnyRef::Spatial(g) => {
            let report = py
                .detach(|| pgo::spectrum::spectrum3(&g.graph, options.weights, k))
                .map_err(|e| to_py(py, e))?;
            let unconverged = report
                .components
                .iter()
                .filter(|c| !c.eigen_converged)
                .map(|c| c.first_id)
                .collect();
            let json = pgo::cli::spectrum::JsonReport3 {
                report: &report,
                warnings: g.warnings.clone(),
            };
            let json = pgo::cli::common::to_json_line(&json).map_err(|e| to_py(py, e))?;
            return Ok((json, unconverged));
        }
    };
    let report = py
        .detach(|| pgo::spectrum::spectrum(&g.graph, &options))
        .map_err(|e| to_py(py, e))?;
    let unconverged = report
        .components
        .iter()
        .filter(|c| !c.eigen_converged)
        .map(|c| c.first_id)
        .collect();
    let json = pgo::cli::spectrum::JsonReport {
        report: &report,
        warnings: g.warnings.clone(),
    };
    let json = pgo::cli::common::to_json_line(&json).map_err(|e| to_py(py, e))?;
    Ok((json, unconverged))
}

/// The extension module of the Python package `pgo` (see pgo/__init__.py).
#[pymodule]
fn _pgo(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<Graph>()?;
    m.add_class::<Graph3>()?;
    m.add_function(wrap_pyfunction!(read_path, m)?)?;
    m.add_function(wrap_pyfunction!(read_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(certify, m)?)?;
    m.add_function(wrap_pyfunction!(spectrum, m)?)?;
    m.add("PgoError", py.get_type::<PgoError>())?;
    m.add("ParseError", py.get_type::<ParseError>())?;
    m.add("VERSION", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
