//! The reader shared by g2o and TORO files: the input in chunks (parsed by [`super::block`]),
//! then the graph assembled from them: ids resolved, the dialect decided per file (docs/formats.md
//! §7.2), never per tag, noise matrices checked.

use super::block::{Block, EdgeTag, Family, make_error, mixed_tags, parse_block};
use super::options::ReadOptions;
use super::{Dialect, Format};
use crate::error::{Location, ParseError, ParseErrorKind, Warning};
use crate::graph::{
    Edge, LandmarkForm, Landmarks, Observation, Pose2, PoseGraph, SymMat3, VertexId,
};
use std::collections::HashMap;
use std::io::Read;

/// What the reader decided and noticed.
#[derive(Debug, Clone)]
pub struct ReadReport {
    pub format: Format,
    /// Why: "flag", "extension" or "tags".
    pub format_reason: &'static str,
    pub dialect: Dialect,
    /// Why, in words (e.g. "EDGE_SE2 tags").
    pub dialect_reason: String,
    pub warnings: Vec<Warning>,
    /// Number of lines read.
    pub lines: usize,
    /// The line of each edge of the graph, in its order (1-based; planar graphs only, empty for
    /// a 3D graph).
    pub edge_lines: Vec<usize>,
    /// Vertigo's switchable and max-mixture lines, if the file has any (their edges are in the
    /// graph as plain loop closures).
    pub vertigo: Option<crate::vertigo::Vertigo>,
}

/// Reads a pose graph from a file path, or from stdin when `path` is `-`.
pub fn read_path(path: &str, options: &ReadOptions) -> crate::Result<(PoseGraph, ReadReport)> {
    if path == "-" {
        let stdin = std::io::stdin();
        return read(stdin.lock(), "<stdin>", options);
    }
    let file = std::fs::File::open(path).map_err(|e| crate::Error::io(path, e))?;
    let meta = file.metadata().map_err(|e| crate::Error::io(path, e))?;
    if let Some(map) = mapped(&file, &meta) {
        let mut r = Reader::new(path, options, Some(meta.len()));
        r.parse_chunk(&map)?;
        return Ok(r.finish()?);
    }
    read_sized(file, path, options, Some(meta.len()))
}

/// The file mapped into memory, read only, if it is a regular non-empty file of at most
/// [`MMAP_MAX`] bytes (and the map succeeds). Mapping avoids copying the file into fresh memory
/// and takes one page fault per 16 pages instead of one per page (for the 3D reader, which
/// copied its files before: 0.5 to 0.9 ms of the read phase on sphere_bignoise, torus3D and
/// cubicle).
pub(crate) fn mapped(file: &std::fs::File, meta: &std::fs::Metadata) -> Option<memmap2::Mmap> {
    if !(meta.is_file() && meta.len() > 0 && meta.len() <= MMAP_MAX) {
        return None;
    }
    // SAFETY: the map is only read, and only while the caller parses it. If another process
    // truncated the file meanwhile, reading the lost pages would fault (as it would for ripgrep
    // and every other mmap reader); pgo accepts that for speed.
    unsafe { memmap2::Mmap::map(file) }.ok()
}

/// Files up to this size are mapped into memory and parsed in place; larger ones are read in
/// chunks of [`CHUNK`] bytes, so their memory use beyond the graph stays bounded.
const MMAP_MAX: u64 = 64 << 20;

/// Reads a pose graph from `input`; `name` is the path used in messages and for the extension.
///
/// The input is read in chunks of [`CHUNK`] bytes, so memory beyond the graph itself stays
/// bounded; large chunks are parsed by two threads, each on its own half (split at a line
/// boundary), and the halves are merged in file order, so the result, warnings and the error
/// reported (the first in the file) do not depend on the number of threads.
pub fn read<R: Read>(
    input: R,
    name: &str,
    options: &ReadOptions,
) -> crate::Result<(PoseGraph, ReadReport)> {
    read_sized(input, name, options, None)
}

/// [`read`] knowing the input's size in bytes, if it is known, to size buffers once.
fn read_sized<R: Read>(
    input: R,
    name: &str,
    options: &ReadOptions,
    size: Option<u64>,
) -> crate::Result<(PoseGraph, ReadReport)> {
    let mut r = Reader::new(name, options, size);
    r.read_chunks(input)?;
    Ok(r.finish()?)
}

/// Bytes read and parsed at a time.
const CHUNK: usize = 8 << 20;
/// Chunks at least this large are parsed by two threads. Below it a second thread costs more
/// than it saves in a fresh process (its start and the page faults of a second set of vectors:
/// measured on city10000.g2o, 1.75 MB, 9.4 ms with two threads against 8.2 ms with one).
const PARALLEL_MIN: usize = 4 << 20;

struct Reader<'o> {
    name: String,
    options: &'o ReadOptions,
    acc: Block,
    lines: usize,
    /// Size of the input in bytes, if known.
    size: Option<u64>,
}

impl<'o> Reader<'o> {
    fn new(name: &str, options: &'o ReadOptions, size: Option<u64>) -> Self {
        Reader {
            name: name.to_string(),
            options,
            acc: Block::default(),
            lines: 0,
            size,
        }
    }

    fn error(&self, line: usize, col: usize, kind: ParseErrorKind) -> ParseError {
        make_error(&self.name, line, col, kind)
    }

    fn read_chunks<R: Read>(&mut self, mut input: R) -> crate::Result<()> {
        // No larger than the file: every byte of the buffer touched costs a page fault.
        let first = self
            .size
            .map_or(CHUNK, |s| (s as usize).saturating_add(1).min(CHUNK));
        let mut buf = vec![0u8; first.max(4096)];
        let mut filled = 0;
        loop {
            if filled == buf.len() {
                // A single line longer than the buffer.
                buf.resize(2 * buf.len(), 0);
            }
            let mut eof = false;
            while filled < buf.len() {
                match input.read(&mut buf[filled..]) {
                    Ok(0) => {
                        eof = true;
                        break;
                    }
                    Ok(n) => filled += n,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => return Err(crate::Error::io(self.name.clone(), e)),
                }
            }
            let end = if eof {
                filled
            } else {
                match memchr::memrchr(b'\n', &buf[..filled]) {
                    Some(p) => p + 1,
                    None => continue,
                }
            };
            self.parse_chunk(&buf[..end])?;
            buf.copy_within(end..filled, 0);
            filled -= end;
            if eof {
                return Ok(());
            }
        }
    }

    /// Parses complete lines following those read so far.
    fn parse_chunk(&mut self, bytes: &[u8]) -> Result<(), ParseError> {
        let first_line = self.lines + 1;
        let lines = memchr::memchr_iter(b'\n', bytes).count() + 1;
        self.lines += lines - usize::from(bytes.last().is_none_or(|&c| c == b'\n'));
        // The first block is given room for the whole file's lines, estimated from this chunk's
        // density, so later blocks append without reallocating (unused capacity is never
        // touched, so it costs no memory).
        let capacity = match self.size {
            Some(size) if self.acc.edges.capacity() == 0 && !bytes.is_empty() => {
                (lines as u128 * u128::from(size) / bytes.len() as u128) as usize + 16
            }
            _ => lines,
        };
        let split = (bytes.len() >= PARALLEL_MIN
            && std::thread::available_parallelism().is_ok_and(|n| n.get() > 1))
        .then(|| memchr::memchr(b'\n', &bytes[bytes.len() / 2..]).map(|k| bytes.len() / 2 + k + 1))
        .flatten();
        let reference = self.acc.first_edge_tag.clone();
        let Some(mid) = split else {
            let block = parse_block(
                &self.name,
                self.options,
                bytes,
                first_line,
                reference,
                capacity,
            )?;
            return self.append(block);
        };
        let (a, b) = bytes.split_at(mid);
        let b_first_line = first_line + memchr::memchr_iter(b'\n', a).count();
        let (name, options) = (self.name.as_str(), self.options);
        let (ra, rb) = std::thread::scope(|s| {
            let hb = s.spawn(|| parse_block(name, options, b, b_first_line, None, 0));
            let ra = parse_block(name, options, a, first_line, reference, capacity);
            (ra, hb.join().expect("the parser does not panic"))
        });
        self.append(ra?)?;
        match rb {
            Ok(block) => self.append(block),
            // The second half was parsed without knowing the first's edge tags; parse it again
            // knowing them, so the error reported is the first in the file.
            Err(_) => {
                let reference = self.acc.first_edge_tag.clone();
                let block = parse_block(&self.name, self.options, b, b_first_line, reference, 0)?;
                self.append(block)
            }
        }
    }

    /// Appends the next block in file order.
    fn append(&mut self, b: Block) -> Result<(), ParseError> {
        if let (Some(a), Some(b)) = (&self.acc.first_edge_tag, &b.first_edge_tag)
            && a.family != b.family
            && self.options.dialect.is_none()
        {
            return Err(self.error(b.line, b.col, mixed_tags(a, &b.tag)));
        }
        let acc = &mut self.acc;
        let offset = acc.edges.len();
        acc.kinds
            .extend(b.kinds.into_iter().map(|(k, kind)| (k + offset, kind)));
        extend(&mut acc.switches, b.switches);
        extend(&mut acc.priors, b.priors);
        if acc.first_vertigo_line.is_none() {
            acc.first_vertigo_line = b.first_vertigo_line;
        }
        extend(&mut acc.vertices, b.vertices);
        extend(&mut acc.edges, b.edges);
        extend(&mut acc.sites, b.sites);
        extend(&mut acc.fixed, b.fixed);
        extend(&mut acc.landmarks, b.landmarks);
        extend(&mut acc.observations, b.observations);
        if acc.first_g2o_landmark.is_none() {
            acc.first_g2o_landmark = b.first_g2o_landmark;
        }
        if acc.first_landmark2.is_none() {
            acc.first_landmark2 = b.first_landmark2;
        }
        if acc.first_edge_tag.is_none() {
            acc.first_edge_tag = b.first_edge_tag;
        }
        if acc.first_vertex_family.is_none() {
            acc.first_vertex_family = b.first_vertex_family;
        }
        for (tag, s) in b.unknown {
            match acc.unknown.iter_mut().find(|(t, _)| *t == tag) {
                Some((_, known)) => known.count += s.count,
                None => acc.unknown.push((tag, s)),
            }
        }
        match (&mut acc.equiv, b.equiv) {
            (Some(known), Some(s)) => known.count += s.count,
            (known @ None, s) => *known = s,
            _ => {}
        }
        Ok(())
    }

    fn finish(mut self) -> Result<(PoseGraph, ReadReport), ParseError> {
        if self.acc.vertices.is_empty()
            && self.acc.edges.is_empty()
            && self.acc.observations.is_empty()
            && self.acc.landmarks.is_empty()
        {
            return Err(self.no_graph());
        }
        let (format, format_reason) = self.decide_format();
        let mut warnings = Vec::new();
        let declared = !self.acc.vertices.is_empty();
        let form = self.landmark_form()?;
        let (ids, poses) = self.vertex_table()?;
        let index = IdIndex::new(&ids);
        let (landmark_ids, positions) = self.landmark_table()?;
        let landmark_index = IdIndex::new(&landmark_ids);
        // In g2o's form one id space holds poses and landmarks: an id is one or the other.
        let shared = form == LandmarkForm::G2o && !landmark_ids.is_empty();
        if shared {
            self.check_disjoint()?;
            self.check_kinds()?;
        }
        let observations = self.resolve_observations(form, &index, &landmark_index)?;

        let (dialect, dialect_reason) = self.decide_dialect(format, &mut warnings);
        let mut edges = std::mem::take(&mut self.acc.edges);
        for (e, site) in edges.iter_mut().zip(&self.acc.sites) {
            let (Some(i), Some(j)) = (index.get(e.i as VertexId), index.get(e.j as VertexId))
            else {
                let (id, col) = match index.get(e.i as VertexId) {
                    None => (e.i, site.col_i),
                    Some(_) => (e.j, site.col_j),
                };
                return Err(self.error(
                    site.line as usize,
                    col as usize,
                    ParseErrorKind::UndeclaredVertex { id: id as VertexId },
                ));
            };
            e.i = i;
            e.j = j;
            e.noise = noise_matrix(e.noise.0, dialect);
        }

        let mut fixed = Vec::with_capacity(self.acc.fixed.len());
        let mut is_fixed = vec![false; ids.len()];
        for &(id, line, col) in &self.acc.fixed {
            if shared && landmark_index.get(id).is_some() && index.get(id).is_none() {
                return Err(self.error(line, col, ParseErrorKind::FixedLandmark { id }));
            }
            let k = index
                .get(id)
                .ok_or_else(|| self.error(line, col, ParseErrorKind::UnknownFixed { id }))?;
            if !std::mem::replace(&mut is_fixed[k], true) {
                fixed.push(k);
            }
        }

        if !self.options.allow_indefinite {
            self.check_positive_definite(&edges, dialect)?;
            for (o, raw) in observations.iter().zip(&self.acc.observations) {
                if let Err(pivot) = o.information.check_positive_definite() {
                    return Err(self.error(
                        raw.site.line as usize,
                        raw.site.col_noise as usize,
                        ParseErrorKind::LandmarkNotPositiveDefinite { pivot },
                    ));
                }
            }
        }

        for (tag, s) in &self.acc.unknown {
            warnings.push(self.warning(
                s.first_line,
                format!(
                    "unknown tag '{tag}': {} skipped (first here)",
                    plural(s.count, "line")
                ),
            ));
        }
        if let Some(s) = &self.acc.equiv {
            warnings.push(self.warning(
                s.first_line,
                format!(
                    "EQUIV (vertex equivalence) is not supported: {} skipped (first here); the graph is read without them",
                    plural(s.count, "line")
                ),
            ));
        }
        let vertigo = self.vertigo(edges.len(), &mut warnings);
        warnings.sort_by_key(|w| w.location.line);

        let landmarks_declared = !self.acc.landmarks.is_empty();
        let mut graph = PoseGraph {
            ids,
            poses,
            edges,
            fixed,
            vertices_declared: declared,
            noise: dialect.noise(),
            landmarks: Landmarks {
                ids: landmark_ids,
                positions,
                observations,
                declared: landmarks_declared,
                form,
            },
        };
        if !declared {
            graph.initialize_spanning_tree();
        } else if !landmarks_declared {
            graph.initialize_landmarks();
        }
        let report = ReadReport {
            format,
            format_reason,
            dialect,
            dialect_reason,
            warnings,
            lines: self.lines,
            edge_lines: self.acc.sites.iter().map(|s| s.line as usize).collect(),
            vertigo,
        };
        Ok((graph, report))
    }

    /// The error for an input without vertex and edge lines: empty (`/dev/null`), only comments,
    /// FIX or skipped EQUIV lines, or nothing but unknown tags (binary garbage, another format),
    /// located at the first of those.
    fn no_graph(&self) -> ParseError {
        match self.acc.unknown.iter().min_by_key(|(_, s)| s.first_line) {
            Some((tag, first)) => self.error(
                first.first_line,
                1,
                ParseErrorKind::NothingUnderstood {
                    tag: tag.clone(),
                    lines: self.acc.unknown.iter().map(|(_, s)| s.count).sum(),
                },
            ),
            None => self.error(
                1,
                1,
                ParseErrorKind::NoGraph {
                    empty: self.lines == 0,
                },
            ),
        }
    }

    /// Vertigo's lines, with a warning saying how they are read.
    fn vertigo(
        &mut self,
        edges: usize,
        warnings: &mut Vec<Warning>,
    ) -> Option<crate::vertigo::Vertigo> {
        let first = self.acc.first_vertigo_line?;
        let mut v = crate::vertigo::Vertigo {
            kinds: vec![crate::vertigo::EdgeKind::Plain; edges],
            switches: std::mem::take(&mut self.acc.switches),
            priors: std::mem::take(&mut self.acc.priors),
        };
        for &(k, kind) in &self.acc.kinds {
            v.kinds[k] = kind;
        }
        let (switchable, maxmix) = v.counts();
        warnings.push(self.warning(
            first,
            format!(
                "Vertigo's robust edges (first here): {switchable} EDGE_SE2_SWITCHABLE and {maxmix} EDGE_SE2_MAXMIX read as plain loop closures (candidates for --robust), {} VERTEX_SWITCH and {} EDGE_SWITCH_PRIOR lines not used; all are written back to g2o output",
                v.switches.len(),
                v.priors.len()
            ),
        ));
        Some(v)
    }

    fn warning(&self, line: usize, message: String) -> Warning {
        Warning {
            location: Location {
                path: self.name.clone(),
                line,
                col: 1,
            },
            message,
        }
    }

    fn decide_format(&self) -> (Format, &'static str) {
        if let Some(f) = self.options.format {
            return (f, "flag");
        }
        if let Some(f) = Format::from_extension(&self.name) {
            return (f, "extension");
        }
        let family =
            self.acc
                .first_vertex_family
                .or(self.acc.first_edge_tag.as_ref().map(|t| t.family));
        match family {
            Some(Family::Toro) => (Format::Toro, "tags"),
            _ => (Format::G2o, "tags"),
        }
    }

    /// The dialect: the flag if given; else g2o for `EDGE_SE2` tags and toro-info for
    /// `EDGE2`/`EDGE` tags, except that TORO-tagged files whose information matrices are all
    /// positive definite in g2o order but not all in TORO order are read in g2o order, with a
    /// warning (GTSAM's w20000.txt is such a file, docs/formats.md §8). Files without edges take their
    /// format's dialect.
    fn decide_dialect(&self, format: Format, warnings: &mut Vec<Warning>) -> (Dialect, String) {
        if let Some(d) = self.options.dialect {
            return (d, "flag".into());
        }
        let Some(EdgeTag { family, tag, .. }) = &self.acc.first_edge_tag else {
            return (format.default_dialect(), format!("{format} format"));
        };
        match family {
            Family::G2o => (Dialect::G2o, format!("{tag} tags")),
            Family::Toro => {
                let pd = |d| {
                    self.acc.edges.iter().position(|e| {
                        noise_matrix(e.noise.0, d)
                            .check_positive_definite()
                            .is_err()
                    })
                };
                match (pd(Dialect::ToroInfo), pd(Dialect::G2o)) {
                    (Some(bad), None) => {
                        let line = self.acc.sites[bad].line as usize;
                        warnings.push(self.warning(
                            line,
                            format!(
                                "{tag} lines hold information in g2o order (I11 I12 I13 I22 I23 I33): in TORO order this matrix is not positive definite, in g2o order every edge's is; reading the file in dialect g2o (pass --dialect toro-info to insist on TORO order)"
                            ),
                        ));
                        (
                            Dialect::G2o,
                            format!("{tag} tags, values positive definite only in g2o order"),
                        )
                    }
                    _ => (Dialect::ToroInfo, format!("{tag} tags")),
                }
            }
        }
    }

    fn check_positive_definite(&self, edges: &[Edge], dialect: Dialect) -> Result<(), ParseError> {
        for (e, site) in edges.iter().zip(&self.acc.sites) {
            if let Err(pivot) = e.noise.check_positive_definite() {
                let what = match dialect.noise() {
                    crate::graph::NoiseKind::Information => "information",
                    crate::graph::NoiseKind::Covariance => "covariance",
                };
                let other_order = if dialect.toro_order() {
                    Dialect::G2o
                } else {
                    Dialect::ToroInfo
                };
                // The same six values as written, read in the other order.
                let raw = if dialect.toro_order() {
                    e.noise.to_toro()
                } else {
                    e.noise.0
                };
                let hint = if noise_matrix(raw, other_order)
                    .check_positive_definite()
                    .is_ok()
                {
                    if dialect.toro_order() {
                        " (it is in g2o order: try --dialect g2o)"
                    } else {
                        " (it is in TORO order: try --dialect toro-info)"
                    }
                } else {
                    ""
                };
                return Err(self.error(
                    site.line as usize,
                    site.col_noise as usize,
                    ParseErrorKind::NotPositiveDefinite {
                        what,
                        pivot,
                        dialect: dialect.name(),
                        hint,
                    },
                ));
            }
        }
        Ok(())
    }

    /// The landmark form of the file: g2o's or CPL-SLAM's, never both.
    fn landmark_form(&self) -> Result<LandmarkForm, ParseError> {
        match (&self.acc.first_g2o_landmark, &self.acc.first_landmark2) {
            (Some(a), Some(b)) => {
                let (first, later) = if a.line <= b.line { (a, b) } else { (b, a) };
                Err(self.error(
                    later.line,
                    later.col,
                    ParseErrorKind::MixedLandmarkForms {
                        first: first.tag.clone(),
                        first_line: first.line,
                        tag: later.tag.clone(),
                    },
                ))
            }
            (None, Some(_)) => Ok(LandmarkForm::Landmark2),
            _ => Ok(LandmarkForm::G2o),
        }
    }

    /// Landmarks sorted by id, from their vertex lines, or the ids the observations mention
    /// (positions set later from the poses) when the file has none.
    fn landmark_table(&self) -> Result<(Vec<VertexId>, Vec<[f64; 2]>), ParseError> {
        let v = &self.acc.landmarks;
        if v.is_empty() {
            let mut ids: Vec<VertexId> = self.acc.observations.iter().map(|o| o.landmark).collect();
            ids.sort_unstable();
            ids.dedup();
            let positions = vec![[0.0; 2]; ids.len()];
            return Ok((ids, positions));
        }
        let mut order: Vec<usize> = (0..v.len()).collect();
        order.sort_by_key(|&k| v[k].id);
        let duplicate = order
            .windows(2)
            .filter(|w| v[w[0]].id == v[w[1]].id)
            .min_by_key(|w| w[1]);
        if let Some(w) = duplicate {
            let (first, second) = (&v[w[0]], &v[w[1]]);
            return Err(self.error(
                second.line as usize,
                second.col as usize,
                ParseErrorKind::DuplicateVertex {
                    id: second.id,
                    first_line: first.line as usize,
                },
            ));
        }
        Ok(order.iter().map(|&k| (v[k].id, v[k].position)).unzip())
    }

    /// In the g2o form, no id is declared both as a pose and as a landmark (g2o's rule,
    /// docs/formats.md §2.3): the later declaration is reported.
    fn check_disjoint(&self) -> Result<(), ParseError> {
        if self.acc.vertices.is_empty() || self.acc.landmarks.is_empty() {
            return Ok(());
        }
        let pose_lines: HashMap<VertexId, u32> =
            self.acc.vertices.iter().map(|v| (v.id, v.line)).collect();
        let clash = self
            .acc
            .landmarks
            .iter()
            .filter_map(|l| pose_lines.get(&l.id).map(|&p| (l, p)))
            .min_by_key(|(l, p)| l.line.max(*p));
        if let Some((l, p)) = clash {
            let (line, col, first) = if l.line > p {
                (l.line, l.col, p)
            } else {
                let v = self
                    .acc
                    .vertices
                    .iter()
                    .find(|v| v.id == l.id)
                    .expect("the clash is a pose id");
                (v.line, v.col, l.line)
            };
            return Err(self.error(
                line as usize,
                col as usize,
                ParseErrorKind::DuplicateVertex {
                    id: l.id,
                    first_line: first as usize,
                },
            ));
        }
        Ok(())
    }

    /// In the g2o form, every id is used as one kind of vertex: the kind its vertex line declares,
    /// else the kind of its first use; the first line (in file order) that uses an id as the
    /// other kind is reported.
    fn check_kinds(&self) -> Result<(), ParseError> {
        let mut kind: HashMap<VertexId, bool> = HashMap::new();
        for v in &self.acc.vertices {
            kind.insert(v.id, true);
        }
        for l in &self.acc.landmarks {
            kind.insert(l.id, false);
        }
        // (line, col, id, is a pose) of every reference, in file order.
        let mut refs: Vec<(u32, u32, VertexId, bool)> =
            Vec::with_capacity(2 * (self.acc.edges.len() + self.acc.observations.len()));
        for (e, site) in self.acc.edges.iter().zip(&self.acc.sites) {
            refs.push((site.line, site.col_i, e.i as VertexId, true));
            refs.push((site.line, site.col_j, e.j as VertexId, true));
        }
        for o in &self.acc.observations {
            refs.push((o.site.line, o.site.col_i, o.pose, true));
            refs.push((o.site.line, o.site.col_j, o.landmark, false));
        }
        refs.sort_by_key(|r| (r.0, r.1));
        for (line, col, id, pose) in refs {
            match kind.get(&id) {
                Some(&k) if k != pose => {
                    let what = if pose {
                        ParseErrorKind::NotAPose { id }
                    } else {
                        ParseErrorKind::NotALandmark { id }
                    };
                    return Err(self.error(line as usize, col as usize, what));
                }
                Some(_) => {}
                None => {
                    kind.insert(id, pose);
                }
            }
        }
        Ok(())
    }

    /// Observations with dense indices: the pose must be a pose (declared, if the file has pose
    /// vertex lines), the landmark a landmark.
    fn resolve_observations(
        &self,
        form: LandmarkForm,
        index: &IdIndex,
        landmark_index: &IdIndex,
    ) -> Result<Vec<Observation>, ParseError> {
        let (tag, vertex) = match form {
            LandmarkForm::G2o => ("EDGE_SE2_XY", "VERTEX_XY"),
            LandmarkForm::Landmark2 => ("LANDMARK2", "POINT2"),
        };
        self.acc
            .observations
            .iter()
            .map(|o| {
                let at = |col: u32, kind| self.error(o.site.line as usize, col as usize, kind);
                let pose = index.get(o.pose).ok_or_else(|| {
                    at(
                        o.site.col_i,
                        ParseErrorKind::UndeclaredVertex { id: o.pose },
                    )
                })?;
                let landmark = landmark_index.get(o.landmark).ok_or_else(|| {
                    at(
                        o.site.col_j,
                        ParseErrorKind::UndeclaredLandmark {
                            tag,
                            id: o.landmark,
                            vertex,
                        },
                    )
                })?;
                Ok(Observation {
                    pose,
                    landmark,
                    d: o.d,
                    information: o.information,
                })
            })
            .collect()
    }

    /// Poses sorted by id, from the vertex lines, or the ids the edges and landmark
    /// observations mention (with identity poses, to be composed along a spanning tree) when the
    /// file has no vertex lines.
    fn vertex_table(&self) -> Result<(Vec<VertexId>, Vec<Pose2>), ParseError> {
        if self.acc.vertices.is_empty() {
            let ids = used_ids(
                self.acc
                    .edges
                    .iter()
                    .flat_map(|e| [e.i as VertexId, e.j as VertexId])
                    .chain(self.acc.observations.iter().map(|o| o.pose)),
            );
            let poses = vec![Pose2::IDENTITY; ids.len()];
            return Ok((ids, poses));
        }
        // The vertices are in file order: a stable sort by id keeps the lines of one id in it.
        let v = &self.acc.vertices;
        let mut order: Vec<u32> = (0..v.len() as u32).collect();
        order.sort_by_key(|&k| v[k as usize].id);
        // The duplicate declared earliest in the file is reported.
        let duplicate = order
            .windows(2)
            .filter(|w| v[w[0] as usize].id == v[w[1] as usize].id)
            .min_by_key(|w| w[1]);
        if let Some(w) = duplicate {
            let (first, second) = (&v[w[0] as usize], &v[w[1] as usize]);
            return Err(self.error(
                second.line as usize,
                second.col as usize,
                ParseErrorKind::DuplicateVertex {
                    id: second.id,
                    first_line: first.line as usize,
                },
            ));
        }
        Ok(order
            .iter()
            .map(|&k| (v[k as usize].id, v[k as usize].pose))
            .unzip())
    }
}

/// The distinct ids of `refs`, ascending: marked in a table where they are dense enough
/// ([`dense_ids`], as for [`IdIndex`]), else sorted. Edges-only files number their poses 0..n
/// (a sort of their 2m references took a third of the read's final phase on kitti_02 and
/// cityTrees10000).
fn used_ids(refs: impl Iterator<Item = VertexId> + Clone) -> Vec<VertexId> {
    let (count, max) = refs
        .clone()
        .fold((0usize, 0usize), |(c, m), id| (c + 1, m.max(id as usize)));
    if dense_ids(max, count) {
        let mut seen = vec![false; max + 1];
        for id in refs {
            seen[id as usize] = true;
        }
        return (0..=max as VertexId)
            .zip(seen)
            .filter_map(|(id, s)| s.then_some(id))
            .collect();
    }
    let mut ids: Vec<VertexId> = refs.collect();
    ids.sort_unstable();
    ids.dedup();
    ids
}

/// Appends `b` to `a`, taking `b`'s buffer when `a` is empty (the usual case of a file that fits
/// in one chunk).
fn extend<T>(a: &mut Vec<T>, mut b: Vec<T>) {
    if a.is_empty() {
        *a = b;
    } else {
        a.append(&mut b);
    }
}

fn noise_matrix(values: [f64; 6], dialect: Dialect) -> SymMat3 {
    if dialect.toro_order() {
        SymMat3::from_toro(values)
    } else {
        SymMat3(values)
    }
}

fn plural(n: usize, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
}

/// Whether `count` ids up to `max` are dense enough for a table indexed by id (at most four
/// entries per id, plus a small table's worth).
fn dense_ids(max: usize, count: usize) -> bool {
    max <= 4 * count + 1024
}

/// File id -> dense index: a table when ids are dense enough ([`dense_ids`]), else a hash map.
enum IdIndex {
    Table(Vec<u32>),
    Map(HashMap<VertexId, usize>),
}

impl IdIndex {
    fn new(ids: &[VertexId]) -> Self {
        let max = ids.last().map_or(0, |&m| m as usize);
        if dense_ids(max, ids.len()) {
            let mut t = vec![u32::MAX; max + 1];
            for (k, &id) in ids.iter().enumerate() {
                t[id as usize] = k as u32;
            }
            IdIndex::Table(t)
        } else {
            IdIndex::Map(ids.iter().enumerate().map(|(k, &id)| (id, k)).collect())
        }
    }

    fn get(&self, id: VertexId) -> Option<usize> {
        match self {
            IdIndex::Table(t) => t
                .get(id as usize)
                .filter(|&&k| k != u32::MAX)
                .map(|&k| k as usize),
            IdIndex::Map(m) => m.get(&id).copied(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The distinct ids marked in a table or sorted ([`used_ids`]) against a sort and dedup of
    /// the same references: dense ids (edges-only files), sparse ones (above the table's
    /// reach), repeated ones, none.
    #[test]
    fn used_ids_are_the_sorted_distinct_references() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = |bound: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % bound) as VertexId
        };
        for (count, bound) in [
            (0, 1),
            (1, 1),
            (7, 3),
            (500, 400),
            (500, 3000),
            (300, 1 << 30),
        ] {
            let refs: Vec<VertexId> = (0..count).map(|_| next(bound)).collect();
            let mut expected = refs.clone();
            expected.sort_unstable();
            expected.dedup();
            assert_eq!(
                used_ids(refs.iter().copied()),
                expected,
                "{count} below {bound}"
            );
        }
    }
}
