//! Writers for both formats (docs/formats.md §7.3): vertices first, sorted by id, isolated
//! ones included; edges in input order; the FIX ids as one line at the end, where GTSAM's reader
//! tolerates it (docs/formats.md §5.6); every float in shortest round-trip form, never NaN or inf.

use super::{Dialect, Format, g2o, reader3, toro};
use crate::error::Error;
use crate::graph::{LandmarkForm, PoseGraph};
use crate::graph3::{Form3, Graph3};
use crate::vertigo::{self, EdgeKind, Vertigo};
use std::io::Write;
use std::path::Path;

/// How to write a graph.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WriteOptions {
    pub format: Format,
    /// Order of the noise values; its kind (information or covariance) must be the graph's.
    pub dialect: Dialect,
}

impl WriteOptions {
    /// `format` in its default dialect ([`Format::default_dialect`]).
    pub fn of(format: Format) -> Self {
        WriteOptions {
            format,
            dialect: format.default_dialect(),
        }
    }
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
    write_named(
        graph,
        Estimate::of(graph),
        None,
        options,
        None,
        true,
        out,
        "<stdout>",
    )
}

/// The values written on a graph's vertex lines: its poses and landmark positions, in its
/// order (the graph's own, [`Estimate::of`], or a solver's beside it, [`stage_graph`]).
#[derive(Clone, Copy)]
pub struct Estimate<'a> {
    pub poses: &'a [crate::graph::Pose2],
    pub landmarks: &'a [[f64; 2]],
}

impl<'a> Estimate<'a> {
    /// The graph's own poses and landmark positions.
    pub fn of(graph: &'a PoseGraph) -> Self {
        Estimate {
            poses: &graph.poses,
            landmarks: &graph.landmarks.positions,
        }
    }
}

/// The lines of a written graph that its estimate does not change, its edges' and its landmark
/// observations', formatted ahead of the write ([`constant_lines`], [`write_path_prepared`]; a
/// 3D graph's edges' with [`constant_lines3`], [`write3_path_prepared`]):
/// the bytes [`write()`] gives them, each line formatted by itself, so a tool can have them
/// formatted while it solves.
pub struct ConstantLines {
    options: WriteOptions,
    /// A 3D graph's ([`constant_lines3`]).
    spatial: bool,
    edges: usize,
    observations: usize,
    edge_lines: Vec<u8>,
    observation_lines: Vec<u8>,
}

impl ConstantLines {
    /// Whether these lines can stand for `graph`'s in a file written with `options`: as many
    /// edges and observations, the same format and dialect. (That they are the same graph's and
    /// Vertigo lines' is the caller's part: [`write_path_prepared`].)
    fn fit(&self, graph: &PoseGraph, options: WriteOptions) -> bool {
        !self.spatial
            && self.options == options
            && self.edges == graph.edges.len()
            && self.observations == graph.landmarks.observations.len()
    }

    /// [`ConstantLines::fit`] for a 3D graph written in `format`.
    fn fit3(&self, graph: &Graph3, format: Format) -> bool {
        self.spatial && self.options.format == format && self.edges == graph.edges.len()
    }
}

/// The edges' and the landmark observations' lines of `graph` (with `vertigo`'s edge kinds) as
/// [`write()`] would write them with `options`.
pub fn constant_lines(
    graph: &PoseGraph,
    vertigo: Option<&Vertigo>,
    options: WriteOptions,
) -> ConstantLines {
    let edges = EdgeLines {
        graph,
        vertigo,
        edge_tag: edge_tag(options.format),
        toro_order: options.dialect.toro_order(),
    };
    let m = graph.edges.len();
    let mut edge_lines = Vec::with_capacity(m * 160);
    for k in 0..m {
        edges.line(k, &mut edge_lines);
    }
    let marks = &graph.landmarks;
    let mut observation_lines = Vec::with_capacity(marks.observations.len() * 96);
    for k in 0..marks.observations.len() {
        observation_line(graph, k, &mut observation_lines);
    }
    ConstantLines {
        options,
        spatial: false,
        edges: m,
        observations: marks.observations.len(),
        edge_lines,
        observation_lines,
    }
}

/// The edges' lines of a 3D graph as [`write3`] writes them in `format`; `None` where `format`
/// is not the graph's form (which [`write3`] refuses).
pub fn constant_lines3(graph: &Graph3, format: Format) -> Option<ConstantLines> {
    let (_, edge_tag) = tags3(graph, format).ok()?;
    let mut edge_lines = Vec::with_capacity(graph.edges.len() * 400);
    for e in &graph.edges {
        edge_line3(graph, edge_tag, e, &mut edge_lines);
    }
    Some(ConstantLines {
        options: WriteOptions::of(format),
        spatial: true,
        edges: graph.edges.len(),
        observations: 0,
        edge_lines,
        observation_lines: Vec::new(),
    })
}

/// The edge tag of a format.
fn edge_tag(format: Format) -> &'static str {
    match format {
        Format::G2o => g2o::EDGE,
        Format::Toro => toro::EDGE,
    }
}

/// Appends the line of landmark observation k.
fn observation_line(graph: &PoseGraph, k: usize, buf: &mut Vec<u8>) {
    let marks = &graph.landmarks;
    let o = &marks.observations[k];
    let tag = match marks.form {
        LandmarkForm::G2o => g2o::LANDMARK_EDGE,
        LandmarkForm::Landmark2 => g2o::LANDMARK2,
    };
    buf.extend_from_slice(tag.as_bytes());
    let _ = write!(buf, " {} {}", graph.ids[o.pose], marks.ids[o.landmark]);
    end_line(o.d.iter().chain(&o.information.0).copied(), buf);
}

/// Writes `graph` with `estimate` on its vertex lines to `out` (`name` in errors), the edges' and
/// observations' lines from `lines` where they fit. `share`: whether the last edges' lines may be
/// formatted on a thread of their own (not where this write itself runs beside other work).
#[allow(clippy::too_many_arguments)]
fn write_named<W: Write>(
    graph: &PoseGraph,
    estimate: Estimate<'_>,
    vertigo: Option<&Vertigo>,
    options: WriteOptions,
    lines: Option<&ConstantLines>,
    share: bool,
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
    if estimate.poses.len() != graph.poses.len()
        || estimate.landmarks.len() != graph.landmarks.positions.len()
    {
        return Err(Error::Invalid(format!(
            "an estimate of {} poses and {} landmarks for a graph of {} and {}",
            estimate.poses.len(),
            estimate.landmarks.len(),
            graph.poses.len(),
            graph.landmarks.positions.len()
        )));
    }
    check_finite(graph, estimate)?;
    if options.format == Format::Toro && !graph.landmarks.is_empty() {
        return Err(Error::Invalid(format!(
            "TORO has no landmark type: this graph has {} landmarks; write it as g2o (VERTEX_XY, EDGE_SE2_XY) instead",
            graph.landmarks.len()
        )));
    }
    let landmark_vertex = match graph.landmarks.form {
        LandmarkForm::G2o => g2o::LANDMARK_VERTEX,
        LandmarkForm::Landmark2 => g2o::POINT2,
    };
    let vertex_tag = match options.format {
        Format::G2o => g2o::VERTEX,
        Format::Toro => toro::VERTEX,
    };
    let lines = lines.filter(|l| l.fit(graph, options));
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
        edge_tag: edge_tag(options.format),
        toro_order: options.dialect.toro_order(),
    };
    // Formatted ahead, the edges' lines are written as they are.
    let m = if lines.is_some() {
        0
    } else {
        graph.edges.len()
    };
    let split = share
        && m >= PARALLEL_EDGES
        && std::thread::available_parallelism().is_ok_and(|n| n.get() > 1);
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
        for (id, pose) in graph.ids.iter().zip(estimate.poses) {
            buf.extend_from_slice(vertex_tag.as_bytes());
            let _ = write!(buf, " {id}");
            end_line(pose.values(), &mut buf);
            put(&mut buf, &mut out)?;
        }
        for (id, p) in marks.ids.iter().zip(estimate.landmarks) {
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
    if let Some(lines) = lines {
        out.write_all(&buf).map_err(io)?;
        buf.clear();
        out.write_all(&lines.edge_lines).map_err(io)?;
        out.write_all(&lines.observation_lines).map_err(io)?;
    } else {
        for k in 0..marks.observations.len() {
            observation_line(graph, k, &mut buf);
            put(&mut buf, &mut out)?;
        }
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

fn check_finite(graph: &PoseGraph, estimate: Estimate<'_>) -> crate::Result<()> {
    if let Some(k) = estimate
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
    if let Some(k) = estimate
        .landmarks
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
    write_path_prepared(graph, vertigo, options, path, None)
}

/// [`write_path_with`], the edges' and observations' lines taken from `lines` where given:
/// [`constant_lines`] of the same graph (its estimate aside) and Vertigo lines. Lines made for
/// another format or dialect, or another count of edges or observations, are not used.
pub fn write_path_prepared(
    graph: &PoseGraph,
    vertigo: Option<&Vertigo>,
    options: WriteOptions,
    path: &str,
    lines: Option<&ConstantLines>,
) -> crate::Result<()> {
    write_atomic(path, |out, name| {
        write_named(
            graph,
            Estimate::of(graph),
            vertigo,
            options,
            lines,
            true,
            out,
            name,
        )
    })
}

/// [`write_path`] for a 3D graph: the same temporary file and rename, the lines of
/// [`write3`].
pub fn write3_path(graph: &Graph3, format: Format, path: &str) -> crate::Result<()> {
    write3_path_prepared(graph, format, path, None)
}

/// [`write3_path`] with the edges' lines formatted ahead ([`constant_lines3`]) where `lines`
/// holds them for this graph and format: the same bytes.
pub fn write3_path_prepared(
    graph: &Graph3,
    format: Format,
    path: &str,
    lines: Option<&ConstantLines>,
) -> crate::Result<()> {
    write_atomic(path, |out, name| {
        write3_named(graph, format, lines, out, name)
    })
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
    if in_place(target) {
        let file = std::fs::OpenOptions::new()
            .write(true)
            .open(target)
            .map_err(|e| Error::io(path, e))?;
        return write(&mut std::io::BufWriter::new(file), path);
    }
    stage_file(path, write)?.persist()
}

/// Whether `target` is written in place: a device or a FIFO, which a renamed file would replace.
fn in_place(target: &Path) -> bool {
    std::fs::metadata(target).is_ok_and(|meta| !meta.is_file() && !meta.is_dir())
}

/// A file written in full to its temporary file beside its path ([`stage_graph`]) but not in
/// place yet: [`Staged::persist`] renames it over the path; dropped instead, it is removed. The
/// temporary file stays listed for [`remove_temporary_files`] meanwhile. For a file written
/// while it is not yet known to be the one wanted: an estimate before its certificate.
pub struct Staged {
    tmp: tempfile::NamedTempFile,
    path: String,
    _listed: Pending,
}

impl Staged {
    /// Puts the file in place: the rename over its path (as [`write_path`] ends). The file it
    /// replaces goes to the hand given to [`hand_replaced_files_to`], if any.
    pub fn persist(self) -> crate::Result<()> {
        let Staged { tmp, path, _listed } = self;
        let hand = REPLACED.get();
        let replaced = hand.and_then(|_| hold(&path));
        tmp.persist(&path)
            .map_err(|e| Error::io(&path, without_path(e.error)))?;
        if let (Some(hand), Some(file)) = (hand, replaced) {
            hand(file);
        }
        Ok(())
    }
}

/// Where [`Staged::persist`] hands the file that its rename replaces ([`hand_replaced_files_to`]).
static REPLACED: std::sync::OnceLock<fn(std::fs::File)> = std::sync::OnceLock::new();

/// Has every rename of an output over its path ([`write_path`], [`write_atomic`],
/// [`Staged::persist`]) hand the file it replaces, held open, to `hand` (once per process; a
/// second call changes nothing). The replaced file's data are freed when its last descriptor
/// closes, not in the rename: on ext4 a rename over a file of 130 to 690 KB took 0.2 to 0.4 ms
/// (its blocks freed), to a new name or over a file held open 0.02 ms. A tool hands it to a
/// thread with time to spare; without a hand the path is not opened and the rename frees the
/// file as before. Linux only (an `O_PATH` descriptor, which needs no permission to read).
pub fn hand_replaced_files_to(hand: fn(std::fs::File)) {
    let _ = REPLACED.set(hand);
}

/// The file at `path` itself (not a symbolic link's target), held open without reading it;
/// `None` where there is none or elsewhere than Linux.
fn hold(path: &str) -> Option<std::fs::File> {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::OpenOptionsExt;
        std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_PATH | libc::O_NOFOLLOW)
            .open(path)
            .ok()
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = path;
        None
    }
}

/// [`write_atomic`]'s temporary file, written by `write`, with its final permissions, not yet
/// renamed.
fn stage_file(
    path: &str,
    write: impl FnOnce(&mut dyn Write, &str) -> crate::Result<()>,
) -> crate::Result<Staged> {
    let target = Path::new(path);
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
    let listed = Pending::list(tmp.path());
    write(&mut std::io::BufWriter::new(tmp.as_file()), path)?;
    set_default_permissions(tmp.path()).map_err(io)?;
    Ok(Staged {
        tmp,
        path: path.to_string(),
        _listed: listed,
    })
}

/// Whether [`stage_graph`] stages a file for `path`: not stdout, a device or a FIFO.
pub fn stages(path: &str) -> bool {
    path != "-" && !in_place(Path::new(path))
}

/// [`write_path_prepared`] up to the rename, for a path that names a regular file or nothing
/// yet, with `estimate` on the vertex lines (no copy of the graph needed): the file written in
/// full beside it, every line formatted on this thread (it writes beside other work), and
/// returned [`Staged`]. On Linux the system is asked to start writing the file's pages back
/// (sync_file_range), as ext4 does at a rename over an existing file (its auto_da_alloc) and
/// would do at [`Staged::persist`], so that the rename finds them under way. `None` for stdout,
/// devices and FIFOs, which are written in place when the estimate is known
/// ([`write_path_prepared`]).
pub fn stage_graph(
    graph: &PoseGraph,
    estimate: Estimate<'_>,
    vertigo: Option<&Vertigo>,
    options: WriteOptions,
    path: &str,
    lines: Option<&ConstantLines>,
) -> crate::Result<Option<Staged>> {
    if !stages(path) {
        return Ok(None);
    }
    let staged = stage_file(path, |out, name| {
        write_named(graph, estimate, vertigo, options, lines, false, out, name)
    })?;
    #[cfg(target_os = "linux")]
    // SAFETY: sync_file_range on the temporary file's open descriptor, the whole file; it
    // reads and writes no memory of ours. A refusal leaves the writeback to the rename.
    unsafe {
        use std::os::fd::AsRawFd;
        libc::sync_file_range(
            staged.tmp.as_file().as_raw_fd(),
            0,
            0,
            libc::SYNC_FILE_RANGE_WRITE,
        );
    }
    Ok(Some(staged))
}

/// Writes a 3D graph to `out` in `format`, which must be the graph's form (quaternions are
/// written as g2o `VERTEX_SE3:QUAT`/`EDGE_SE3:QUAT`, Euler angles as TORO `VERTEX3`/`EDGE3`;
/// converting one into the other would change values, and the information matrix's rotation
/// coordinates, so it is refused): vertices sorted by id, edges in input order, the 21
/// information values in the file's order, FIX ids on one line at the end, every number in
/// shortest round-trip form, so the file read back gives every value bit for bit.
pub fn write3<W: Write>(graph: &Graph3, format: Format, mut out: W) -> crate::Result<()> {
    write3_named(graph, format, None, &mut out, "<stdout>")
}

/// The vertex and edge tags of `graph` written in `format`, which must be its form.
fn tags3(graph: &Graph3, format: Format) -> crate::Result<(&'static str, &'static str)> {
    Ok(match (format, graph.form) {
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
    })
}

/// Appends the line of 3D edge `e`.
fn edge_line3(graph: &Graph3, edge_tag: &str, e: &crate::graph3::Edge3, buf: &mut Vec<u8>) {
    buf.extend_from_slice(edge_tag.as_bytes());
    let _ = write!(buf, " {} {}", graph.ids[e.i], graph.ids[e.j]);
    end_line(e.measurement.values().chain(e.information.0), buf);
}

fn write3_named(
    graph: &Graph3,
    format: Format,
    lines: Option<&ConstantLines>,
    out: &mut dyn Write,
    name: &str,
) -> crate::Result<()> {
    let (vertex_tag, edge_tag) = tags3(graph, format)?;
    check_finite3(graph)?;
    let lines = lines.filter(|l| l.fit3(graph, format));
    let io = |e| Error::io(name, e);
    let mut buf: Vec<u8> = Vec::with_capacity(1 << 16);
    let mut put = |buf: &mut Vec<u8>, last: bool| -> crate::Result<()> {
        if last || buf.len() >= 1 << 16 {
            out.write_all(buf).map_err(io)?;
            buf.clear();
        }
        Ok(())
    };
    let edge_line =
        |e: &crate::graph3::Edge3, buf: &mut Vec<u8>| edge_line3(graph, edge_tag, e, buf);
    // As in 2D ([`write_named`]): with a second core, the last edges' lines are formatted there
    // into a buffer of their own while this thread formats the vertices and the first edges
    // (each line alone, so the bytes are the same). A vertex line has 7 numbers, an edge's 28.
    // Formatted ahead, the edges' lines are written as they are.
    let m = if lines.is_some() {
        0
    } else {
        graph.edges.len()
    };
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
    if let Some(lines) = lines {
        put(&mut buf, true)?;
        out.write_all(&lines.edge_lines).map_err(io)?;
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

/// The temporary files being written now, for [`remove_temporary_files`]: NUL-terminated, so
/// that a signal handler removes them with unlink(2), which allocates nothing.
static PENDING: std::sync::Mutex<Vec<std::ffi::CString>> = std::sync::Mutex::new(Vec::new());

/// [`PENDING`], locked with the interrupt signals blocked on this thread ([`Pending`]'s changes):
/// a handler on this thread never finds the list locked by the code it interrupted, and one on
/// another thread waits a few instructions at most ([`remove_temporary_files`]). `change` must
/// neither allocate nor free: the handler's thread may have been interrupted inside malloc,
/// holding the lock that this thread would then wait for while the handler waits for the list.
fn with_pending<R>(change: impl FnOnce(&mut Vec<std::ffi::CString>) -> R) -> R {
    let _blocked = interrupts::Blocked::new();
    let mut list = PENDING
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    change(&mut list)
}

/// A temporary file listed in [`PENDING`] while this lives.
pub struct Pending(std::ffi::CString);

impl Pending {
    /// Lists `path` (an absolute path, so that it stays right whatever the working directory)
    /// until the returned value is dropped.
    pub fn list(path: &Path) -> Self {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        // A path with a NUL byte cannot name a file, nor be created: nothing to remove then.
        let path =
            std::ffi::CString::new(path.into_os_string().into_encoded_bytes()).unwrap_or_default();
        let mut entry = path.clone();
        // Pushed where the list has room; else a larger list is allocated out of the lock, the
        // entries moved into it inside (no allocation), and the old one freed after.
        while let Err((back, capacity)) = with_pending(|list| {
            if list.len() < list.capacity() {
                list.push(entry);
                Ok(())
            } else {
                Err((entry, 2 * list.capacity() + 4))
            }
        }) {
            let mut larger = Vec::with_capacity(capacity);
            with_pending(|list| {
                if list.len() < capacity {
                    larger.append(list);
                    std::mem::swap(list, &mut larger);
                }
            });
            drop(larger);
            entry = back;
        }
        Pending(path)
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        // Freed out of the lock.
        let removed = with_pending(|list| {
            list.iter()
                .rposition(|p| *p == self.0)
                .map(|k| list.swap_remove(k))
        });
        drop(removed);
    }
}

/// Removes the temporary files being written now (by [`write_path`], or listed with
/// [`Pending::list`]): what an interrupted tool calls before it ends, so that no hidden
/// `.pgo-*.tmp` file is left behind. Returns how many were removed. Async-signal-safe (a tool
/// calls it from its signal handler): it allocates nothing, and waits for the list only while
/// another thread changes it, with the interrupts blocked there.
pub fn remove_temporary_files() -> usize {
    let list = loop {
        match PENDING.try_lock() {
            Ok(list) => break list,
            Err(std::sync::TryLockError::Poisoned(poisoned)) => break poisoned.into_inner(),
            Err(std::sync::TryLockError::WouldBlock) => std::hint::spin_loop(),
        }
    };
    list.iter().filter(|p| interrupts::unlink(p)).count()
}

/// The system calls behind [`PENDING`]'s use in a signal handler.
mod interrupts {
    /// The signals whose handler removes the temporary files (a tool's SIGINT, SIGTERM and
    /// SIGHUP), blocked on this thread while this lives.
    pub struct Blocked {
        #[cfg(unix)]
        before: libc::sigset_t,
    }

    impl Blocked {
        pub fn new() -> Self {
            #[cfg(unix)]
            // SAFETY: sigset_t is a plain C struct, initialized by sigemptyset before use;
            // pthread_sigmask changes this thread's mask only and writes the old one to
            // `before`.
            unsafe {
                let mut set = std::mem::zeroed::<libc::sigset_t>();
                let mut before = std::mem::zeroed::<libc::sigset_t>();
                libc::sigemptyset(&mut set);
                for signal in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
                    libc::sigaddset(&mut set, signal);
                }
                libc::pthread_sigmask(libc::SIG_BLOCK, &set, &mut before);
                Blocked { before }
            }
            #[cfg(not(unix))]
            Blocked {}
        }
    }

    impl Drop for Blocked {
        fn drop(&mut self) {
            #[cfg(unix)]
            // SAFETY: restores the mask that `new` read.
            unsafe {
                libc::pthread_sigmask(libc::SIG_SETMASK, &self.before, std::ptr::null_mut());
            }
        }
    }

    /// Removes the file at `path`; whether it was removed.
    pub fn unlink(path: &std::ffi::CStr) -> bool {
        #[cfg(unix)]
        // SAFETY: unlink(2) reads the NUL-terminated path only.
        unsafe {
            libc::unlink(path.as_ptr()) == 0
        }
        #[cfg(not(unix))]
        std::str::from_utf8(path.to_bytes()).is_ok_and(|path| std::fs::remove_file(path).is_ok())
    }
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

    /// Lines formatted ahead ([`constant_lines`]) give the file [`write_path_with`] writes, byte
    /// for byte: for a pose graph with g2o's landmark types and a FIX, one with CPL-SLAM's
    /// LANDMARK2 lines, one with Vertigo's switchable and max-mixture edges and a plain one, in
    /// g2o and TORO (where TORO has a form for the graph; where not, the same refusal). Lines
    /// made for another format, or for a graph with an edge less, are not used: the file is
    /// still the one written without them.
    #[test]
    fn lines_formatted_ahead_write_the_same_file() {
        let g2o_landmarks = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1.5 0.25 0.125\nVERTEX_XY 7 2 3\n\
            EDGE_SE2 0 1 1.5 0.25 0.125 10 0.5 0 20 0.25 30\n\
            EDGE_SE2_XY 0 7 2 3 4 0.5 5\nEDGE_SE2_XY 1 7 0.5 2.75 6 -0.5 7\nFIX 0\n";
        let landmark2 = "EDGE_SE2 0 1 1 0 0 50 0 0 50 0 100\nEDGE_SE2 1 2 1 0 0.1 50 0 0 50 0 100\n\
            LANDMARK2 0 0 2 1 10 0 10\nLANDMARK2 2 0 0.3 1.1 10 1 10\nLANDMARK2 1 1 -1 2 5 0 5\n";
        let vertigo = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 2 0 0\n\
            EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE_SE2 1 2 1 0 0 1 0 0 1 0 1\n\
            VERTEX_SWITCH 5 1\nEDGE_SE2_SWITCHABLE 0 2 5 2 0 0 1 0 0 1 0 1\n\
            EDGE_SWITCH_PRIOR 5 1 20\nEDGE_SE2_MAXMIX 2 0 0.01 -2 0 0 1 0 0 1 0 1\n";
        let poses = "VERTEX_SE2 3 0 0 0\nVERTEX_SE2 4 1 0.5 0.25\nVERTEX_SE2 9 2 1 -3\n\
            EDGE_SE2 3 4 1 0.5 0.25 10 0.5 0.125 20 0.25 30\nEDGE_SE2 4 9 1 0.5 3 1 0 0 2 0 3\n\
            EDGE_SE2 9 3 -2 -1 3 7 0.75 -0.5 8 0.375 9\nFIX 3\n";
        let dir = tempfile::tempdir().unwrap();
        let path = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
        for (k, text) in [g2o_landmarks, landmark2, vertigo, poses]
            .into_iter()
            .enumerate()
        {
            let (graph, report) =
                super::super::read(text.as_bytes(), "in.g2o", &Default::default()).unwrap();
            let vertigo = report.vertigo.as_ref();
            assert_eq!(
                vertigo.is_some(),
                k == 2,
                "Vertigo's lines are read as such"
            );
            assert_eq!(!graph.landmarks.observations.is_empty(), k < 2);
            for format in [Format::G2o, Format::Toro] {
                let options = WriteOptions {
                    format,
                    dialect: format.default_dialect(),
                };
                let other = WriteOptions {
                    format: match format {
                        Format::G2o => Format::Toro,
                        Format::Toro => Format::G2o,
                    },
                    dialect: format.default_dialect(),
                };
                let mut fewer = graph.clone();
                fewer.edges.pop();
                let plain = write_path_with(&graph, vertigo, options, &path("plain"))
                    .map(|()| std::fs::read(path("plain")).unwrap());
                for lines in [
                    constant_lines(&graph, vertigo, options),
                    constant_lines(&graph, vertigo, other),
                    constant_lines(&fewer, None, options),
                ] {
                    let ahead =
                        write_path_prepared(&graph, vertigo, options, &path("ahead"), Some(&lines))
                            .map(|()| std::fs::read(path("ahead")).unwrap());
                    match (&plain, &ahead) {
                        (Ok(a), Ok(b)) => assert!(a == b, "graph {k}, {format:?}"),
                        (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
                        _ => panic!("graph {k}, {format:?}: {plain:?} against {ahead:?}"),
                    }
                }
                // TORO has a form for the plain pose graph only.
                assert_eq!(plain.is_ok(), format == Format::G2o || k == 3);
            }
        }
    }

    /// A file staged with an estimate beside the graph holds what `write_path` writes for the
    /// graph carrying that estimate, byte for byte, once persisted (a graph with landmarks and
    /// FIX; poses and positions moved, so the graph's own would not do); an estimate of another
    /// size is refused; stdout and devices are not staged.
    #[test]
    fn a_staged_file_is_the_written_file_of_its_estimate() {
        let text = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1.5 0.25 0.125\nVERTEX_XY 7 2 3\n\
            EDGE_SE2 0 1 1.5 0.25 0.125 10 0.5 0 20 0.25 30\n\
            EDGE_SE2_XY 0 7 2 3 4 0.5 5\nEDGE_SE2_XY 1 7 0.5 2.75 6 -0.5 7\nFIX 0\n";
        let (graph, _) =
            super::super::read(text.as_bytes(), "in.g2o", &Default::default()).unwrap();
        let poses: Vec<_> = graph
            .poses
            .iter()
            .map(|p| crate::graph::Pose2 {
                x: p.x + 0.1,
                y: p.y - 1e-9,
                theta: p.theta + 3.0,
            })
            .collect();
        let landmarks = vec![[2.5, -3.25]];
        let mut moved = graph.clone();
        moved.poses.clone_from(&poses);
        moved.landmarks.positions.clone_from(&landmarks);
        let dir = tempfile::tempdir().unwrap();
        let path = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
        let options = WriteOptions {
            format: Format::G2o,
            dialect: Dialect::G2o,
        };
        write_path(&moved, options, &path("written.g2o")).unwrap();
        let estimate = Estimate {
            poses: &poses,
            landmarks: &landmarks,
        };
        let staged = stage_graph(&graph, estimate, None, options, &path("staged.g2o"), None);
        staged.unwrap().unwrap().persist().unwrap();
        assert_eq!(
            std::fs::read(path("staged.g2o")).unwrap(),
            std::fs::read(path("written.g2o")).unwrap()
        );
        let mut own = Vec::new();
        write(&graph, options, &mut own).unwrap();
        assert_ne!(std::fs::read(path("staged.g2o")).unwrap(), own);
        let short = Estimate {
            poses: &poses[..1],
            landmarks: &landmarks,
        };
        assert!(stage_graph(&graph, short, None, options, &path("short.g2o"), None).is_err());
        assert!(
            stage_graph(&graph, estimate, None, options, "-", None)
                .unwrap()
                .is_none()
        );
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(".pgo-"))
            .collect();
        assert!(names.is_empty(), "{names:?}");
    }

    /// A rename over an existing output hands the file it replaced to the hand, held open: the
    /// old file itself (its inode, as the system reports it before the write), no longer named
    /// (no link left) and still holding its old bytes, while the path holds the new ones. A
    /// symbolic link at the path is replaced itself, its target untouched; a new path hands
    /// nothing. (The hand is the process's, shared by the tests: the files are told apart by
    /// their inodes.)
    #[cfg(target_os = "linux")]
    #[test]
    fn a_rename_hands_over_the_file_it_replaced() {
        use std::io::Read;
        use std::os::unix::fs::MetadataExt;
        static HANDED: std::sync::Mutex<Vec<std::fs::File>> = std::sync::Mutex::new(Vec::new());
        hand_replaced_files_to(|file| HANDED.lock().unwrap().push(file));
        let handed = |ino: u64| {
            let mut files = HANDED.lock().unwrap();
            let k = files
                .iter()
                .position(|f| f.metadata().unwrap().ino() == ino)?;
            Some(files.swap_remove(k))
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        let name = path.to_str().unwrap();
        write_bytes_path(b"old bytes\n", name).unwrap();
        let old = std::fs::metadata(&path).unwrap().ino();
        write_bytes_path(b"new bytes\n", name).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new bytes\n");
        assert_ne!(std::fs::metadata(&path).unwrap().ino(), old);
        let file = handed(old).expect("the replaced file is handed over");
        let meta = file.metadata().unwrap();
        assert_eq!((meta.nlink(), meta.len()), (0, 10));
        // Its bytes, read through the process's own link to the open file.
        let fd = std::os::fd::AsRawFd::as_raw_fd(&file);
        let mut bytes = Vec::new();
        std::fs::File::open(format!("/proc/self/fd/{fd}"))
            .unwrap()
            .read_to_end(&mut bytes)
            .unwrap();
        assert_eq!(bytes, b"old bytes\n");
        // A symbolic link: replaced, not followed.
        let target = dir.path().join("target.txt");
        std::fs::write(&target, "target\n").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let link_ino = std::fs::symlink_metadata(&link).unwrap().ino();
        write_bytes_path(b"over the link\n", link.to_str().unwrap()).unwrap();
        assert!(handed(link_ino).is_some());
        assert!(std::fs::symlink_metadata(&link).unwrap().is_file());
        assert_eq!(std::fs::read(&target).unwrap(), b"target\n");
        assert_eq!(std::fs::metadata(&target).unwrap().nlink(), 1);
        // A new path: nothing handed (nothing is at the new file's inode before its write).
        let fresh = dir.path().join("fresh.txt");
        write_bytes_path(b"fresh\n", fresh.to_str().unwrap()).unwrap();
        assert!(handed(std::fs::metadata(&fresh).unwrap().ino()).is_none());
    }

    /// The same for 3D graphs ([`constant_lines3`], [`write3_path_prepared`]): a g2o graph
    /// (quaternions, with a FIX and a repeated edge) and a TORO one (Euler angles) give the file
    /// [`write3_path`] writes, byte for byte; lines made for a graph with an edge less, or a
    /// planar graph's lines, are not used, and the format that is not the graph's form has no
    /// lines (and the write is refused as before).
    #[test]
    fn lines_formatted_ahead_write_the_same_3d_file() {
        let info = "1 0 0 0 0 0 2 0 0 0 0 3 0 0 0 4 0 0 5 0 6.5";
        let g2o = format!(
            "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 2 1 0.5 0.25 0.1 0.2 0.3 0.927\n\
             VERTEX_SE3:QUAT 5 2 1 -3 0 0 0.6 0.8\n\
             EDGE_SE3:QUAT 0 2 1 0.5 0.25 0.1 0.2 0.3 0.927 {info}\n\
             EDGE_SE3:QUAT 2 5 1 0.5 -3.25 0 0 0.6 0.8 {info}\n\
             EDGE_SE3:QUAT 2 5 1.125 0.5 -3 0 0 0.6 0.8 {info}\nFIX 0\n"
        );
        let toro = format!(
            "VERTEX3 1 0 0 0 0 0 0\nVERTEX3 4 1 0.5 0.25 0.1 -0.2 0.3\n\
             EDGE3 1 4 1 0.5 0.25 0.1 -0.2 0.3 {info}\nEDGE3 4 1 -1 0.5 0.25 0 0 3 {info}\n"
        );
        let planar = "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE_SE2 1 2 1 0 0 1 0 0 1 0 1\n\
            EDGE_SE2 2 0 1 0 0 1 0 0 1 0 1\n";
        let (planar, _) =
            super::super::read(planar.as_bytes(), "in.g2o", &Default::default()).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
        for (text, form) in [(g2o, Format::G2o), (toro, Format::Toro)] {
            let (graph, _) =
                super::super::read3(text.as_bytes(), "in", &Default::default()).unwrap();
            assert_eq!(graph.edges.len(), if form == Format::G2o { 3 } else { 2 });
            let mut fewer = graph.clone();
            fewer.edges.pop();
            for format in [Format::G2o, Format::Toro] {
                let plain = write3_path(&graph, format, &path("plain"))
                    .map(|()| std::fs::read(path("plain")).unwrap());
                assert_eq!(plain.is_ok(), format == form);
                assert_eq!(constant_lines3(&graph, format).is_some(), format == form);
                let planar_lines = constant_lines(
                    &planar,
                    None,
                    WriteOptions {
                        format,
                        dialect: format.default_dialect(),
                    },
                );
                // As many edges as the g2o graph: only their kind tells them apart.
                assert_eq!(planar_lines.edges, 3);
                let candidates = [
                    constant_lines3(&graph, format),
                    constant_lines3(&fewer, format),
                    Some(planar_lines),
                ];
                for lines in candidates.iter().flatten() {
                    let ahead = write3_path_prepared(&graph, format, &path("ahead"), Some(lines))
                        .map(|()| std::fs::read(path("ahead")).unwrap());
                    match (&plain, &ahead) {
                        (Ok(a), Ok(b)) => assert!(a == b, "{form:?} as {format:?}"),
                        (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
                        _ => panic!("{form:?} as {format:?}: {plain:?} against {ahead:?}"),
                    }
                }
            }
        }
    }

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
        let dir = dir.path().as_os_str().as_encoded_bytes();
        assert!(!with_pending(|list| list
            .iter()
            .any(|p| p.to_bytes().starts_with(dir))));
    }

    /// The list grows out of its lock (its changes allocate nothing): forty files listed at
    /// once are all in it, and none once dropped. (Not removed here: other tests write files
    /// meanwhile, listed in the same list.)
    #[test]
    fn many_temporary_files_are_listed_and_unlisted() {
        let dir = tempfile::tempdir().unwrap();
        let paths: Vec<_> = (0..40)
            .map(|k| dir.path().join(format!(".pgo-{k}.tmp")))
            .collect();
        let listed: Vec<_> = paths.iter().map(|p| Pending::list(p)).collect();
        let bytes = dir.path().as_os_str().as_encoded_bytes();
        let count = || {
            with_pending(|list| {
                list.iter()
                    .filter(|p| p.to_bytes().starts_with(bytes))
                    .count()
            })
        };
        assert_eq!(count(), paths.len());
        drop(listed);
        assert_eq!(count(), 0);
    }

    /// The interrupt signals are blocked only while the list changes: the thread's mask after
    /// listing and unlisting is the one before (else a tool would ignore Ctrl-C from its first
    /// output on).
    #[cfg(unix)]
    #[test]
    fn listing_a_temporary_file_leaves_the_signal_mask_as_it_was() {
        fn mask() -> libc::sigset_t {
            // SAFETY: a null new mask only reads this thread's mask into the zeroed set.
            unsafe {
                let mut set = std::mem::zeroed::<libc::sigset_t>();
                libc::pthread_sigmask(libc::SIG_BLOCK, std::ptr::null(), &mut set);
                set
            }
        }
        let blocked = |set: &libc::sigset_t| {
            [libc::SIGINT, libc::SIGTERM, libc::SIGHUP]
                // SAFETY: sigismember reads the set only.
                .map(|s| unsafe { libc::sigismember(set, s) })
        };
        let before = mask();
        let listed = Pending::list(Path::new("/nonexistent/.pgo-x.tmp"));
        assert_eq!(blocked(&mask()), blocked(&before));
        drop(listed);
        assert_eq!(blocked(&mask()), blocked(&before));
        // Inside a change they are blocked.
        assert_eq!(with_pending(|_| blocked(&mask())), [1, 1, 1]);
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
