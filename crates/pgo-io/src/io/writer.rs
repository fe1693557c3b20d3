//! Writers for both formats (docs/formats.md §7.3): vertices first, sorted by id, isolated
//! ones included; edges in input order; the FIX ids as one line at the end, where GTSAM's reader
//! tolerates it (docs/formats.md §5.6); every float in shortest round-trip form, never NaN or inf.

use super::{Dialect, Format, g2o, reader3, toro};
use crate::error::Error;
use crate::graph::{LandmarkForm, PoseGraph};
use crate::graph3::{Form3, Graph3};
use crate::vertigo::{self, EdgeKind, Vertigo};
use std::io::Write;
use std::path::{Path, PathBuf};

/// How to write a graph.
#[derive(Debug, Clone, Copy)]
pub struct WriteOptions {
    pub format: Format,
    /// Order of the noise values; its kind (information or covariance) must be the graph's.
    pub dialect: Dialect,
}

/// Appends the shortest decimal that parses back to exactly `v`, by the Żmij algorithm (the
/// `zmij` crate, several times faster than the standard library's formatting): plain notation
/// for 1e-5 <= |v| < 1e16 (without a trailing `.0`), exponent notation (`1e-7`, `1.5e+300`)
/// otherwise, so no number is longer than 24 bytes; C++ `>>` reads both. The sign of zero is kept.
pub fn format_f64(v: f64, out: &mut Vec<u8>) {
    debug_assert!(v.is_finite());
    let mut buffer = zmij::Buffer::new();
    let text = buffer.format_finite(v).as_bytes();
    out.extend_from_slice(text.strip_suffix(b".0").unwrap_or(text));
}

/// Writes `graph` to `out`.
pub fn write<W: Write>(graph: &PoseGraph, options: WriteOptions, out: W) -> crate::Result<()> {
    write_named(graph, None, options, out, "<stdout>")
}

fn write_named<W: Write>(
    graph: &PoseGraph,
    vertigo: Option<&Vertigo>,
    options: WriteOptions,
    mut out: W,
    name: &str,
) -> crate::Result<()> {
    if let Some(v) = vertigo {
        if options.format != Format::G2o {
            let (switchable, maxmix) = v.counts();
            return Err(Error::Invalid(format!(
                "the graph has Vertigo's robust lines ({switchable} EDGE_SE2_SWITCHABLE, {maxmix} EDGE_SE2_MAXMIX, {} VERTEX_SWITCH, {} EDGE_SWITCH_PRIOR), which {} has no form for: write g2o",
                v.switches.len(),
                v.priors.len(),
                options.format
            )));
        }
        if v.kinds.len() != graph.edges.len() {
            return Err(Error::Invalid(format!(
                "{} edge kinds for {} edges",
                v.kinds.len(),
                graph.edges.len()
            )));
        }
    }
    if options.dialect.noise() != graph.noise {
        return Err(Error::Invalid(format!(
            "cannot write {:?} matrices in dialect {}",
            graph.noise, options.dialect
        )));
    }
    check_finite(graph)?;
    if options.format == Format::Toro && !graph.landmarks.is_empty() {
        return Err(Error::Invalid(format!(
            "TORO has no landmark type: this graph has {} landmarks; write it as g2o (VERTEX_XY, EDGE_SE2_XY) instead",
            graph.landmarks.len()
        )));
    }
    let (landmark_vertex, observation_tag) = match graph.landmarks.form {
        LandmarkForm::G2o => (g2o::LANDMARK_VERTEX, g2o::LANDMARK_EDGE),
        LandmarkForm::Landmark2 => (g2o::POINT2, g2o::LANDMARK2),
    };
    let (vertex_tag, edge_tag) = match options.format {
        Format::G2o => (g2o::VERTEX, g2o::EDGE),
        Format::Toro => (toro::VERTEX, toro::EDGE),
    };
    let io = |e| Error::io(name, e);
    // Lines are assembled in a buffer flushed in large chunks.
    let mut buf: Vec<u8> = Vec::with_capacity(1 << 16);
    let put = |buf: &mut Vec<u8>, out: &mut W| -> crate::Result<()> {
        if buf.len() >= 1 << 16 {
            out.write_all(buf).map_err(io)?;
            buf.clear();
        }
        Ok(())
    };
    let marks = &graph.landmarks;
    // The edges' lines: with a second core, the last ones are formatted there into a buffer of
    // their own while this thread writes the vertices and the first edges (each line is
    // formatted alone, so the bytes are the same either way). A vertex line is about a third of
    // an edge's.
    let edges = EdgeLines {
        graph,
        vertigo,
        edge_tag,
        toro_order: options.dialect.toro_order(),
    };
    let m = graph.edges.len();
    let split =
        m >= PARALLEL_EDGES && std::thread::available_parallelism().is_ok_and(|n| n.get() > 1);
    let mid = if split {
        m.saturating_sub(graph.poses.len() / 3) / 2
    } else {
        m
    };
    std::thread::scope(|scope| -> crate::Result<()> {
        let last = split.then(|| {
            scope.spawn(|| {
                let mut last = Vec::with_capacity((m - mid) * 160);
                for k in mid..m {
                    edges.line(k, &mut last);
                }
                last
            })
        });
        for (id, pose) in graph.ids.iter().zip(&graph.poses) {
            buf.extend_from_slice(vertex_tag.as_bytes());
            let _ = write!(buf, " {id}");
            end_line(pose.values(), &mut buf);
            put(&mut buf, &mut out)?;
        }
        for (id, p) in marks.ids.iter().zip(&marks.positions) {
            buf.extend_from_slice(landmark_vertex.as_bytes());
            let _ = write!(buf, " {id}");
            end_line(p.iter().copied(), &mut buf);
            put(&mut buf, &mut out)?;
        }
        for s in vertigo.map_or(&[][..], |v| &v.switches) {
            let _ = write!(buf, "{} {} ", vertigo::VERTEX_SWITCH, s.id);
            format_f64(s.value, &mut buf);
            buf.push(b'\n');
            put(&mut buf, &mut out)?;
        }
        for k in 0..mid {
            edges.line(k, &mut buf);
            put(&mut buf, &mut out)?;
        }
        if let Some(last) = last {
            let last = last.join().expect("formatting lines does not panic");
            out.write_all(&buf).map_err(io)?;
            buf.clear();
            out.write_all(&last).map_err(io)?;
        }
        Ok(())
    })?;
    for o in &marks.observations {
        buf.extend_from_slice(observation_tag.as_bytes());
        let _ = write!(buf, " {} {}", graph.ids[o.pose], marks.ids[o.landmark]);
        end_line(o.d.iter().chain(&o.information.0).copied(), &mut buf);
        put(&mut buf, &mut out)?;
    }
    for p in vertigo.map_or(&[][..], |v| &v.priors) {
        let _ = write!(buf, "{} {} ", vertigo::EDGE_SWITCH_PRIOR, p.id);
        format_f64(p.prior, &mut buf);
        buf.push(b' ');
        format_f64(p.information, &mut buf);
        buf.push(b'\n');
        put(&mut buf, &mut out)?;
    }
    if !graph.fixed.is_empty() {
        buf.extend_from_slice(g2o::FIX.as_bytes());
        for &k in &graph.fixed {
            let _ = write!(buf, " {}", graph.ids[k]);
        }
        buf.push(b'\n');
    }
    out.write_all(&buf).map_err(io)?;
    out.flush().map_err(io)
}

/// Ends a line: each value after a space, then the newline.
fn end_line(values: impl IntoIterator<Item = f64>, buf: &mut Vec<u8>) {
    for v in values {
        buf.push(b' ');
        format_f64(v, buf);
    }
    buf.push(b'\n');
}

/// Edges from which [`write`] formats the lines of two halves on two threads: at least this many.
const PARALLEL_EDGES: usize = 8192;

/// Edges from which [`write3`] formats the lines of two halves on two threads: a 3D edge's line
/// has three times the numbers of a planar one.
const PARALLEL_EDGES_3D: usize = PARALLEL_EDGES / 3;

/// What an edge's line needs: the graph, its Vertigo kinds, the edge tag and the noise order.
struct EdgeLines<'a> {
    graph: &'a PoseGraph,
    vertigo: Option<&'a Vertigo>,
    edge_tag: &'a str,
    toro_order: bool,
}

impl EdgeLines<'_> {
    /// Appends the line of edge k.
    fn line(&self, k: usize, buf: &mut Vec<u8>) {
        let (graph, e) = (self.graph, &self.graph.edges[k]);
        let kind = self.vertigo.map_or(EdgeKind::Plain, |v| v.kinds[k]);
        match kind {
            EdgeKind::Plain => {
                buf.extend_from_slice(self.edge_tag.as_bytes());
                let _ = write!(buf, " {} {}", graph.ids[e.i], graph.ids[e.j]);
            }
            EdgeKind::Switchable { switch } => {
                let _ = write!(
                    buf,
                    "{} {} {} {switch}",
                    vertigo::EDGE_SWITCHABLE,
                    graph.ids[e.i],
                    graph.ids[e.j]
                );
            }
            EdgeKind::MaxMix { weight } => {
                let _ = write!(
                    buf,
                    "{} {} {} ",
                    vertigo::EDGE_MAXMIX,
                    graph.ids[e.i],
                    graph.ids[e.j]
                );
                format_f64(weight, buf);
            }
        }
        let noise = if self.toro_order {
            e.noise.to_toro()
        } else {
            e.noise.0
        };
        end_line(e.measurement.values().into_iter().chain(noise), buf);
    }
}

fn check_finite(graph: &PoseGraph) -> crate::Result<()> {
    if let Some(k) = graph
        .poses
        .iter()
        .position(|p| !p.values().iter().all(|v| v.is_finite()))
    {
        return Err(Error::Invalid(format!(
            "pose of vertex {} is not finite and cannot be written",
            graph.ids[k]
        )));
    }
    if let Some(e) = graph.edges.iter().find(|e| {
        !e.measurement
            .values()
            .iter()
            .chain(&e.noise.0)
            .all(|v| v.is_finite())
    }) {
        return Err(Error::Invalid(format!(
            "edge {} -> {} holds a value that is not finite and cannot be written",
            graph.ids[e.i], graph.ids[e.j]
        )));
    }
    let marks = &graph.landmarks;
    if let Some(k) = marks
        .positions
        .iter()
        .position(|p| !p.iter().all(|v| v.is_finite()))
    {
        return Err(Error::Invalid(format!(
            "position of landmark {} is not finite and cannot be written",
            marks.ids[k]
        )));
    }
    if let Some(o) = marks
        .observations
        .iter()
        .find(|o| !o.d.iter().chain(&o.information.0).all(|v| v.is_finite()))
    {
        return Err(Error::Invalid(format!(
            "observation of landmark {} from pose {} holds a value that is not finite and cannot be written",
            marks.ids[o.landmark], graph.ids[o.pose]
        )));
    }
    Ok(())
}

/// The directory a file `path` is written in (through a temporary file there).
fn directory_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// The error of an operation on a temporary file, without the temporary file's name (messages
/// name the user's path only).
fn without_path(e: std::io::Error) -> std::io::Error {
    match e.raw_os_error() {
        Some(code) => std::io::Error::from_raw_os_error(code),
        None => std::io::Error::new(e.kind(), e.kind().to_string()),
    }
}

/// Checks, before any long work, that [`write_path`] can write `path`: `-` (stdout) and an
/// existing device or FIFO (written in place) always can; otherwise `path` must not be (or end
/// like) a directory, and its directory must exist and let a file be created there (a probe file
/// is created and removed at once, as the temporary file of the write will be). A write can
/// still fail later (a full disk); this catches the mistakes of the command line.
pub fn check_output(path: &str) -> crate::Result<()> {
    if path == "-" {
        return Ok(());
    }
    let fail = |what: String| Error::io(path, std::io::Error::other(what));
    let target = Path::new(path);
    if path.ends_with('/') || path.ends_with(std::path::MAIN_SEPARATOR) {
        return Err(fail("is a directory, not a file to write".into()));
    }
    match std::fs::metadata(target) {
        Ok(meta) if meta.is_dir() => {
            return Err(fail("is a directory, not a file to write".into()));
        }
        Ok(meta) if !meta.is_file() => return Ok(()),
        Ok(_) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(Error::io(path, e)),
    }
    let dir = directory_of(target);
    match std::fs::metadata(dir) {
        Ok(meta) if meta.is_dir() => {}
        Ok(_) => return Err(fail(format!("{} is not a directory", dir.display()))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(fail(format!("directory {} does not exist", dir.display())));
        }
        Err(e) => return Err(fail(format!("directory {}: {e}", dir.display()))),
    }
    tempfile::Builder::new()
        .prefix(".pgo-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map(|probe| {
            // Listed too: an interrupt in between leaves nothing either.
            let _listed = Pending::list(probe.path());
            drop(probe);
        })
        .map_err(|e| {
            fail(format!(
                "cannot create a file in directory {}: {}",
                dir.display(),
                without_path(e)
            ))
        })
}

/// Writes `graph` to `path` (stdout for `-`). A file is written to a temporary file in the same
/// directory and renamed over `path` only once complete, so a failure never leaves a partial or
/// truncated file; while it exists, the temporary file is listed for
/// [`remove_temporary_files`] (a tool's interrupt handler). Errors name `path`, never the
/// temporary file.
pub fn write_path(graph: &PoseGraph, options: WriteOptions, path: &str) -> crate::Result<()> {
    write_path_with(graph, None, options, path)
}

/// [`write_path`] with Vertigo's lines of the graph (g2o only: its switch variables after the
/// pose vertices, each edge with its own tag, the switch priors after the edges).
pub fn write_path_with(
    graph: &PoseGraph,
    vertigo: Option<&Vertigo>,
    options: WriteOptions,
    path: &str,
) -> crate::Result<()> {
    write_atomic(path, |out, name| {
        write_named(graph, vertigo, options, out, name)
    })
}

/// [`write_path`] for a 3D graph: the same temporary file and rename, the lines of
/// [`write3`].
pub fn write3_path(graph: &Graph3, format: Format, path: &str) -> crate::Result<()> {
    write_atomic(path, |out, name| write3_named(graph, format, out, name))
}

/// Writes a file the way [`write_path`] does, whatever it holds: `write(out, name)` writes to
/// `out` (stdout for `-`, a device or FIFO in place, else a temporary file renamed over `path`
/// once complete and listed for [`remove_temporary_files`]), `name` being what its errors call
/// the output.
pub fn write_atomic(
    path: &str,
    write: impl FnOnce(&mut dyn Write, &str) -> crate::Result<()>,
) -> crate::Result<()> {
    if path == "-" {
        let stdout = std::io::stdout();
        return write(&mut stdout.lock(), "<stdout>");
    }
    let target = Path::new(path);
    // A device or a FIFO (/dev/null, /dev/stdout, a named pipe) is written in place: renaming a
    // temporary file over it would replace the device with a regular file.
    if let Ok(meta) = std::fs::metadata(target)
        && !meta.is_file()
        && !meta.is_dir()
    {
        let file = std::fs::OpenOptions::new()
            .write(true)
            .open(target)
            .map_err(|e| Error::io(path, e))?;
        return write(&mut std::io::BufWriter::new(file), path);
    }
    if target.is_dir() {
        // Else the rename of the temporary file over it fails with a less telling message.
        return Err(Error::Invalid(format!("{path}: is a directory")));
    }
    let io = |e| Error::io(path, without_path(e));
    let tmp = tempfile::Builder::new()
        .prefix(".pgo-")
        .suffix(".tmp")
        .tempfile_in(directory_of(target))
        .map_err(io)?;
    let _listed = Pending::list(tmp.path());
    write(&mut std::io::BufWriter::new(tmp.as_file()), path)?;
    set_default_permissions(tmp.path()).map_err(io)?;
    tmp.persist(target).map_err(|e| io(e.error))?;
    Ok(())
}

/// Writes a 3D graph to `out` in `format`, which must be the graph's form (quaternions are
/// written as g2o `VERTEX_SE3:QUAT`/`EDGE_SE3:QUAT`, Euler angles as TORO `VERTEX3`/`EDGE3`;
/// converting one into the other would change values, and the information matrix's rotation
/// coordinates, so it is refused): vertices sorted by id, edges in input order, the 21
/// information values in the file's order, FIX ids on one line at the end, every number in
/// shortest round-trip form, so the file read back gives every value bit for bit.
pub fn write3<W: Write>(graph: &Graph3, format: Format, mut out: W) -> crate::Result<()> {
    write3_named(graph, format, &mut out, "<stdout>")
}

fn write3_named(
    graph: &Graph3,
    format: Format,
    out: &mut dyn Write,
    name: &str,
) -> crate::Result<()> {
    let (vertex_tag, edge_tag) = match (format, graph.form) {
        (Format::G2o, Form3::G2o) => (reader3::G2O_VERTEX, reader3::G2O_EDGE),
        (Format::Toro, Form3::Toro) => (reader3::TORO_VERTEX, reader3::TORO_EDGE),
        (Format::Toro, Form3::G2o) => {
            return Err(Error::Invalid(
                "a 3D g2o graph (quaternions) cannot be written as TORO (VERTEX3/EDGE3, Euler angles) without loss: the angles would be computed, not copied, and the information matrices are over other rotation coordinates (qx qy qz against roll pitch yaw); write it as g2o".into(),
            ));
        }
        (Format::G2o, Form3::Toro) => {
            return Err(Error::Invalid(
                "a 3D TORO graph (Euler angles) cannot be written as g2o (VERTEX_SE3:QUAT/EDGE_SE3:QUAT, quaternions) without loss: the quaternions would be computed, not copied, and the information matrices are over other rotation coordinates (roll pitch yaw against qx qy qz); write it as TORO".into(),
            ));
        }
    };
    check_finite3(graph)?;
    let io = |e| Error::io(name, e);
    let mut buf: Vec<u8> = Vec::with_capacity(1 << 16);
    let mut put = |buf: &mut Vec<u8>, last: bool| -> crate::Result<()> {
        if last || buf.len() >= 1 << 16 {
            out.write_all(buf).map_err(io)?;
            buf.clear();
        }
        Ok(())
    };
    let edge_line = |e: &crate::graph3::Edge3, buf: &mut Vec<u8>| {
        buf.extend_from_slice(edge_tag.as_bytes());
        let _ = write!(buf, " {} {}", graph.ids[e.i], graph.ids[e.j]);
        end_line(e.measurement.values().chain(e.information.0), buf);
    };
    // As in 2D ([`write_named`]): with a second core, the last edges' lines are formatted there
    // into a buffer of their own while this thread formats the vertices and the first edges
    // (each line alone, so the bytes are the same). A vertex line has 7 numbers, an edge's 28.
    let m = graph.edges.len();
    let split =
        m >= PARALLEL_EDGES_3D && std::thread::available_parallelism().is_ok_and(|n| n.get() > 1);
    let mid = if split {
        m.saturating_sub(graph.poses.len() / 4) / 2
    } else {
        m
    };
    std::thread::scope(|scope| -> crate::Result<()> {
        let last = split.then(|| {
            scope.spawn(|| {
                let mut last = Vec::with_capacity((m - mid) * 400);
                for e in &graph.edges[mid..] {
                    edge_line(e, &mut last);
                }
                last
            })
        });
        for (id, pose) in graph.ids.iter().zip(&graph.poses) {
            buf.extend_from_slice(vertex_tag.as_bytes());
            let _ = write!(buf, " {id}");
            end_line(pose.values(), &mut buf);
            put(&mut buf, false)?;
        }
        for e in &graph.edges[..mid] {
            edge_line(e, &mut buf);
            put(&mut buf, false)?;
        }
        if let Some(last) = last {
            let last = last.join().expect("formatting lines does not panic");
            put(&mut buf, true)?;
            buf = last;
        }
        Ok(())
    })?;
    if !graph.fixed.is_empty() {
        buf.extend_from_slice(g2o::FIX.as_bytes());
        for &k in &graph.fixed {
            let _ = write!(buf, " {}", graph.ids[k]);
        }
        buf.push(b'\n');
    }
    put(&mut buf, true)?;
    out.flush().map_err(io)
}

fn check_finite3(graph: &Graph3) -> crate::Result<()> {
    if let Some(k) = graph
        .poses
        .iter()
        .position(|p| !p.values().all(f64::is_finite))
    {
        return Err(Error::Invalid(format!(
            "pose of vertex {} is not finite and cannot be written",
            graph.ids[k]
        )));
    }
    if let Some(e) = graph.edges.iter().find(|e| {
        !e.measurement
            .values()
            .chain(e.information.0)
            .all(f64::is_finite)
    }) {
        return Err(Error::Invalid(format!(
            "edge {} -> {} holds a value that is not finite and cannot be written",
            graph.ids[e.i], graph.ids[e.j]
        )));
    }
    Ok(())
}

/// Writes `bytes` to the file `path` as [`write_path`] writes a graph ([`write_atomic`]): for the
/// side outputs of the tools (e.g. marginal covariances).
pub fn write_bytes_path(bytes: &[u8], path: &str) -> crate::Result<()> {
    write_atomic(path, |out, name| {
        out.write_all(bytes)
            .and_then(|_| out.flush())
            .map_err(|e| Error::io(name, e))
    })?;
    Ok(())
}

/// The temporary files being written now, for [`remove_temporary_files`].
static PENDING: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

fn pending() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    PENDING
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// A temporary file listed in [`PENDING`] while this lives.
pub struct Pending(PathBuf);

impl Pending {
    /// Lists `path` (an absolute path, so that it stays right whatever the working directory)
    /// until the returned value is dropped.
    pub fn list(path: &Path) -> Self {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        pending().push(path.clone());
        Pending(path)
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        let mut list = pending();
        if let Some(k) = list.iter().rposition(|p| *p == self.0) {
            list.swap_remove(k);
        }
    }
}

/// Removes the temporary files being written now (by [`write_path`], or listed with
/// [`Pending::list`]): what an interrupted tool calls before it ends, so that no hidden
/// `.pgo-*.tmp` file is left behind. Returns how many were removed.
pub fn remove_temporary_files() -> usize {
    let list = pending();
    list.iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
        .count()
}

/// Temporary files are created private (0600); a written graph gets the usual 0644.
#[cfg(unix)]
fn set_default_permissions(path: &std::path::Path) -> std::io::Result<()> {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o644))
}

#[cfg(not(unix))]
fn set_default_permissions(_: &std::path::Path) -> std::io::Result<()> {
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_are_checked_and_errors_name_the_users_path() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path().to_str().unwrap();
        assert!(check_output("-").is_ok());
        assert!(check_output(&format!("{d}/out.g2o")).is_ok());
        for (path, says) in [
            (format!("{d}/no/such/out.g2o"), "does not exist"),
            (d.to_string(), "is a directory"),
            (format!("{d}/new/"), "is a directory"),
        ] {
            let e = check_output(&path).unwrap_err().to_string();
            assert!(e.starts_with(&format!("{path}: ")), "{e}");
            assert!(e.contains(says), "{e}");
            assert!(!e.contains(".pgo-"), "{e}");
        }
        // The probe leaves nothing.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        // A write that fails names the user's path, not the temporary file.
        let graph = PoseGraph::with_edges(vec![crate::graph::Pose2::IDENTITY], vec![]);
        let options = WriteOptions {
            format: Format::G2o,
            dialect: Dialect::G2o,
        };
        let path = format!("{d}/missing/out.g2o");
        let e = write_path(&graph, options, &path).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!("{path}: ")) && !e.contains(".pgo-"),
            "{e}"
        );
    }

    #[test]
    fn listed_temporary_files_are_removed_on_request_and_unlisted_when_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join(".pgo-a.tmp");
        let b = dir.path().join(".pgo-b.tmp");
        std::fs::write(&a, "a").unwrap();
        std::fs::write(&b, "b").unwrap();
        let listed_a = Pending::list(&a);
        {
            let _listed_b = Pending::list(&b);
        }
        // b is no longer listed: only a is removed.
        assert!(remove_temporary_files() >= 1);
        assert!(!a.exists() && b.exists());
        drop(listed_a);
        assert!(!pending().iter().any(|p| p.starts_with(dir.path())));
    }

    fn fmt(v: f64) -> String {
        let mut out = Vec::new();
        format_f64(v, &mut out);
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn shortest_round_trip() {
        assert_eq!(fmt(0.0), "0");
        assert_eq!(fmt(-0.0), "-0");
        assert_eq!(fmt(1.0), "1");
        assert_eq!(fmt(-0.5), "-0.5");
        assert_eq!(fmt(44.721359549995796), "44.721359549995796");
        assert_eq!(fmt(1e-7), "1e-7");
        assert_eq!(fmt(1e-5), "0.00001");
        assert_eq!(fmt(6.95335e-310), "6.95335e-310");
        assert_eq!(fmt(1.5e300), "1.5e+300");
        assert_eq!(fmt(1e16), "1e+16");
        assert_eq!(fmt(1e15), "1000000000000000");
        assert_eq!(fmt(-10.0), "-10");
        assert_eq!(fmt(123456789012345.6), "123456789012345.6");
        // Every value, including awkward ones, parses back to the same bits.
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..100_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits(x);
            if v.is_finite() {
                let s = fmt(v);
                assert_eq!(s.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{s}");
                assert!(s.len() <= 24, "{s}");
            }
        }
    }
}
