//! The pose graph as read from a file: poses, relative-pose measurements, information matrices
//! and FIX ids, kept exactly as written, plus the dense internal index used by the numerics.
//!
//! Conventions (docs/method.md §2.1, docs/formats.md §2.3): an edge `(i, j, z)` measures the pose of `j` in the
//! frame of `i`, z ≈ x_i⁻¹ · x_j. In the paper's complex notation (eq. (2)-(4)) an edge carries
//! Δ_ij = dx + i·dy and R_ij = e^{i·dθ}.

use std::borrow::Cow;

use nalgebra::{Isometry2, Matrix3, Vector2};

/// A vertex id as written in the file. g2o stores ids as a signed 32-bit `int` and refuses
/// negative ones (docs/formats.md §2.3), so the valid range is `0..=2^31 - 1`.
pub type VertexId = u32;

/// Largest id g2o, TORO and GTSAM can all read back.
pub const MAX_VERTEX_ID: VertexId = i32::MAX as VertexId;

/// A planar pose (x, y, θ) exactly as read: θ is not normalized and every value keeps its bits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose2 {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
}

impl Pose2 {
    pub const IDENTITY: Pose2 = Pose2 {
        x: 0.0,
        y: 0.0,
        theta: 0.0,
    };

    pub fn new(x: f64, y: f64, theta: f64) -> Self {
        Pose2 { x, y, theta }
    }

    /// The rigid motion this pose stands for (θ taken modulo 2π).
    pub fn to_isometry(self) -> Isometry2<f64> {
        Isometry2::new(Vector2::new(self.x, self.y), self.theta)
    }

    /// A pose from a rigid motion, with θ in (-π, π].
    pub fn from_isometry(iso: &Isometry2<f64>) -> Self {
        Pose2 {
            x: iso.translation.vector.x,
            y: iso.translation.vector.y,
            theta: iso.rotation.angle(),
        }
    }

    pub fn values(self) -> [f64; 3] {
        [self.x, self.y, self.theta]
    }
}

/// What the six numbers of an edge's noise block mean.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum NoiseKind {
    /// Information matrix Ω (inverse covariance), as g2o and TORO define it.
    Information,
    /// Covariance matrix Σ = Ω⁻¹, as in GTSAM's `.graph` files (docs/formats.md §5.5).
    Covariance,
}

/// A symmetric 3x3 matrix over (x, y, θ), stored as its upper triangle in g2o order
/// `[m00, m01, m02, m11, m12, m22]` (docs/formats.md §2.2). Whether it is an information or a
/// covariance matrix is a property of the graph ([`PoseGraph::noise`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SymMat3(pub [f64; 6]);

impl SymMat3 {
    pub const IDENTITY: SymMat3 = SymMat3([1.0, 0.0, 0.0, 1.0, 0.0, 1.0]);

    /// From TORO's order `ff fs ss rr fr sr` = m00 m01 m11 m22 m02 m12 (docs/formats.md §3.1).
    pub fn from_toro(t: [f64; 6]) -> Self {
        SymMat3([t[0], t[1], t[4], t[2], t[5], t[3]])
    }

    /// In TORO's order `ff fs ss rr fr sr` (docs/formats.md §3.1: TORO = (G0, G1, G3, G5, G2, G4)).
    pub fn to_toro(self) -> [f64; 6] {
        let g = self.0;
        [g[0], g[1], g[3], g[5], g[2], g[4]]
    }

    pub fn matrix(self) -> Matrix3<f64> {
        let [a, b, c, d, e, f] = self.0;
        Matrix3::new(a, b, c, b, d, e, c, e, f)
    }

    fn from_matrix_upper(m: &Matrix3<f64>) -> Self {
        SymMat3([
            m[(0, 0)],
            m[(0, 1)],
            m[(0, 2)],
            m[(1, 1)],
            m[(1, 2)],
            m[(2, 2)],
        ])
    }

    /// Positive definiteness by Cholesky factorization M = L Lᵀ, written out for 3x3;
    /// `Err(k)` names the first (0-based) pivot that is not positive (or not finite).
    pub fn check_positive_definite(self) -> Result<(), usize> {
        // Rejects zero, negative and NaN pivots.
        let positive =
            |d: f64| d.partial_cmp(&0.0) == Some(std::cmp::Ordering::Greater) && d.is_finite();
        let [m00, m01, m02, m11, m12, m22] = self.0;
        if !positive(m00) {
            return Err(0);
        }
        let l00 = m00.sqrt();
        let (l10, l20) = (m01 / l00, m02 / l00);
        let d1 = m11 - l10 * l10;
        if !positive(d1) {
            return Err(1);
        }
        let l21 = (m12 - l20 * l10) / d1.sqrt();
        if !positive(m22 - l20 * l20 - l21 * l21) {
            return Err(2);
        }
        Ok(())
    }

    /// The inverse (information <-> covariance); `None` if singular.
    pub fn inverse(self) -> Option<Self> {
        let inv = self.matrix().try_inverse()?;
        let sym = (inv + inv.transpose()) * 0.5;
        sym.iter()
            .all(|v| v.is_finite())
            .then(|| Self::from_matrix_upper(&sym))
    }
}

/// A relative-pose measurement between two poses (dense indices into [`PoseGraph::ids`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge {
    pub i: usize,
    pub j: usize,
    /// z = (dx, dy, dθ): the pose of `j` in the frame of `i`.
    pub measurement: Pose2,
    /// Upper triangle of the noise matrix, g2o order; see [`PoseGraph::noise`].
    pub noise: SymMat3,
}

/// A symmetric 2x2 information matrix over (x, y) of a landmark observation, stored as its
/// upper triangle `[I11, I12, I22]`, the order of `EDGE_SE2_XY` and `LANDMARK2` lines
/// (docs/formats.md §2.1, §9.1). Landmark observations always hold information matrices,
/// whatever the dialect of the pose edges.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SymMat2(pub [f64; 3]);

impl SymMat2 {
    pub const IDENTITY: SymMat2 = SymMat2([1.0, 0.0, 1.0]);

    /// Positive definiteness by Cholesky factorization; `Err(k)` names the first (0-based)
    /// pivot that is not positive (or not finite).
    pub fn check_positive_definite(self) -> Result<(), usize> {
        let positive =
            |d: f64| d.partial_cmp(&0.0) == Some(std::cmp::Ordering::Greater) && d.is_finite();
        let [a, b, d] = self.0;
        if !positive(a) {
            return Err(0);
        }
        let l = b / a.sqrt();
        if !positive(d - l * l) {
            return Err(1);
        }
        Ok(())
    }
}

/// An observation of landmark `landmark` from pose `pose` (dense indices into
/// [`Landmarks::ids`] and [`PoseGraph::ids`]): `d` = (dx, dy) is the landmark's position in the
/// frame of the pose, d ≈ R(θ_i)ᵀ (l − p_i); in complex notation d_ik = dx + i·dy and the term
/// of f is ν |l_k − p_i − r_i d_ik|².
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    pub pose: usize,
    pub landmark: usize,
    pub d: [f64; 2],
    /// Information matrix Ω_ik of (dx, dy).
    pub information: SymMat2,
}

/// How landmarks are written in a file (docs/formats.md §2.1, §9.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum LandmarkForm {
    /// g2o's types: `VERTEX_XY id x y`, `EDGE_SE2_XY pose point dx dy I11 I12 I22`; landmark
    /// ids share one id space with the poses.
    #[default]
    G2o,
    /// CPL-SLAM's `LANDMARK2 pose landmark dx dy I11 I12 I22` (positions, if any, on
    /// `POINT2 id x y` lines, which CPL-SLAM skips); landmark ids live in their own id space.
    Landmark2,
}

/// The landmarks of a graph: 2D points observed from poses. Empty for a pose graph.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Landmarks {
    /// File ids, strictly ascending (in the poses' id space for [`LandmarkForm::G2o`], disjoint
    /// from the pose ids; in their own for [`LandmarkForm::Landmark2`]).
    pub ids: Vec<VertexId>,
    /// Position of each landmark: from vertex lines, or from its first observation by a pose
    /// when the file has none ([`PoseGraph::initialize_spanning_tree`]).
    pub positions: Vec<[f64; 2]>,
    /// Observations in input order.
    pub observations: Vec<Observation>,
    /// Whether `positions` came from landmark vertex lines in the file.
    pub declared: bool,
    pub form: LandmarkForm,
}

impl Landmarks {
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Dense index of a landmark's file id.
    pub fn index_of(&self, id: VertexId) -> Option<usize> {
        self.ids.binary_search(&id).ok()
    }

    /// The number of observations of each landmark.
    pub fn observation_counts(&self) -> Vec<usize> {
        let mut count = vec![0usize; self.ids.len()];
        for o in &self.observations {
            count[o.landmark] += 1;
        }
        count
    }
}

/// A planar pose graph.
///
/// Poses are indexed densely `0..n` in ascending id order (`ids[k]` is the file's id of pose
/// `k`); edges keep the input order, duplicates and direction.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseGraph {
    /// File ids, strictly ascending.
    pub ids: Vec<VertexId>,
    /// Initial estimate per pose: the VERTEX line as read, or composed along a spanning tree when
    /// the file has no vertex lines ([`PoseGraph::initialize_spanning_tree`]).
    pub poses: Vec<Pose2>,
    pub edges: Vec<Edge>,
    /// Dense indices of fixed poses, in the order of the FIX lines, without repeats.
    pub fixed: Vec<usize>,
    /// Whether `poses` came from vertex lines in the file.
    pub vertices_declared: bool,
    /// Whether edge noise blocks are information or covariance matrices.
    pub noise: NoiseKind,
    /// Landmarks and their observations (empty for a pose graph).
    pub landmarks: Landmarks,
}

impl PoseGraph {
    /// A graph built in code: poses with ids 0..n−1 and the given estimate, edges with
    /// information matrices, no fixed poses (as if read from a g2o file with vertex lines).
    pub fn with_edges(poses: Vec<Pose2>, edges: Vec<Edge>) -> Self {
        PoseGraph {
            ids: (0..poses.len() as VertexId).collect(),
            poses,
            edges,
            fixed: Vec::new(),
            vertices_declared: true,
            noise: NoiseKind::Information,
            landmarks: Landmarks::default(),
        }
    }

    pub fn num_poses(&self) -> usize {
        self.ids.len()
    }

    /// Dense index of a file id.
    pub fn index_of(&self, id: VertexId) -> Option<usize> {
        self.ids.binary_search(&id).ok()
    }

    /// Edge information matrix Ω_e, inverting a covariance if the graph holds covariances.
    /// `None` only for a singular covariance.
    pub fn information(&self, e: &Edge) -> Option<SymMat3> {
        match self.noise {
            NoiseKind::Information => Some(e.noise),
            NoiseKind::Covariance => e.noise.inverse(),
        }
    }

    /// Converts every noise block to `kind` (inverting 3x3 matrices if the kind changes).
    /// Returns the position of the first edge whose matrix is singular, if any.
    pub fn convert_noise(&mut self, kind: NoiseKind) -> Result<(), usize> {
        if self.noise == kind {
            return Ok(());
        }
        let mut inverted = Vec::with_capacity(self.edges.len());
        for (k, e) in self.edges.iter().enumerate() {
            inverted.push(e.noise.inverse().ok_or(k)?);
        }
        for (e, m) in self.edges.iter_mut().zip(inverted) {
            e.noise = m;
        }
        self.noise = kind;
        Ok(())
    }

    /// Renumbers the ids densely as `0..n` in ascending order of the old ids; landmarks
    /// follow as `n..n + m` in the g2o form (one id space), `0..m` in the LANDMARK2 form.
    pub fn reindex(&mut self) {
        for (k, id) in self.ids.iter_mut().enumerate() {
            *id = k as VertexId;
        }
        let base = match self.landmarks.form {
            LandmarkForm::G2o => self.ids.len(),
            LandmarkForm::Landmark2 => 0,
        };
        for (k, id) in self.landmarks.ids.iter_mut().enumerate() {
            *id = (base + k) as VertexId;
        }
    }

    /// Puts the landmarks in g2o's form (one id space with the poses): landmark id `k` becomes
    /// `k + offset`. The offset is `offset` if given, else 0 when no landmark id is a pose id
    /// (CPL-SLAM's victoriaPark.g2o numbers both in one sequence), else the largest pose id + 1
    /// (cityTrees10000.g2o's landmarks 0..99 share ids with poses 0..99). Returns the offset used;
    /// [`PoseGraph::landmarks_to_landmark2`] with it gives back the ids. Already in g2o form:
    /// nothing changes and the offset is 0. Errors if a shifted id would collide with a pose id
    /// or exceed [`MAX_VERTEX_ID`].
    pub fn landmarks_to_g2o(&mut self, offset: Option<VertexId>) -> Result<VertexId, String> {
        if self.landmarks.form == LandmarkForm::G2o {
            return match offset {
                None | Some(0) => Ok(0),
                Some(_) => Err("the landmarks are in g2o form already: no offset applies".into()),
            };
        }
        let collides = |offset: VertexId| {
            self.landmarks
                .ids
                .iter()
                .find(|&&id| self.index_of(id + offset).is_some())
                .copied()
        };
        let top = self.landmarks.ids.last().copied().unwrap_or(0);
        let offset = match offset {
            Some(o) => o,
            None => match collides(0) {
                None => 0,
                Some(_) => self.ids.last().map_or(0, |&m| m + 1),
            },
        };
        if u64::from(top) + u64::from(offset) > u64::from(MAX_VERTEX_ID) {
            return Err(format!(
                "landmark id {top} + offset {offset} exceeds the largest id {MAX_VERTEX_ID}"
            ));
        }
        if let Some(id) = collides(offset) {
            return Err(format!(
                "landmark {id} + offset {offset} = {} is a pose id",
                id + offset
            ));
        }
        for id in &mut self.landmarks.ids {
            *id += offset;
        }
        self.landmarks.form = LandmarkForm::G2o;
        Ok(offset)
    }

    /// Puts the landmarks in CPL-SLAM's LANDMARK2 form (their own id space): landmark id `k`
    /// becomes `k − offset` (0 if not given), the inverse of [`PoseGraph::landmarks_to_g2o`].
    /// Errors if some landmark id is below the offset.
    pub fn landmarks_to_landmark2(&mut self, offset: Option<VertexId>) -> Result<(), String> {
        let offset = offset.unwrap_or(0);
        if self.landmarks.form == LandmarkForm::Landmark2 {
            return match offset {
                0 => Ok(()),
                _ => Err("the landmarks are in LANDMARK2 form already: no offset applies".into()),
            };
        }
        if let Some(&low) = self.landmarks.ids.first()
            && low < offset
        {
            return Err(format!("landmark {low} is below the offset {offset}"));
        }
        for id in &mut self.landmarks.ids {
            *id -= offset;
        }
        self.landmarks.form = LandmarkForm::Landmark2;
        Ok(())
    }

    /// Adjacency in compressed form over the nodes `0..n` (poses) and `n..n + m` (landmarks):
    /// for node `u`, `adj[start[u]..start[u + 1]]` lists its links, edge `k` as `k` and
    /// observation `k` as `edges.len() + k`, edges first, each in input order.
    pub fn incidence(&self) -> (Vec<usize>, Vec<usize>) {
        let n = self.num_poses();
        let nodes = n + self.landmarks.len();
        let mut start = vec![0usize; nodes + 1];
        for e in &self.edges {
            start[e.i + 1] += 1;
            start[e.j + 1] += 1;
        }
        for o in &self.landmarks.observations {
            start[o.pose + 1] += 1;
            start[n + o.landmark + 1] += 1;
        }
        for k in 0..nodes {
            start[k + 1] += start[k];
        }
        let mut fill = start.clone();
        let mut adj = vec![0usize; start[nodes]];
        for (k, e) in self.edges.iter().enumerate() {
            adj[fill[e.i]] = k;
            fill[e.i] += 1;
            adj[fill[e.j]] = k;
            fill[e.j] += 1;
        }
        let m = self.edges.len();
        for (k, o) in self.landmarks.observations.iter().enumerate() {
            adj[fill[o.pose]] = m + k;
            fill[o.pose] += 1;
            adj[fill[n + o.landmark]] = m + k;
            fill[n + o.landmark] += 1;
        }
        (start, adj)
    }

    /// The node at the other end of link `k` (see [`PoseGraph::incidence`]) from node `u`.
    fn other_end(&self, k: usize, u: usize) -> usize {
        match self.edges.get(k) {
            Some(e) => {
                if e.i == u {
                    e.j
                } else {
                    e.i
                }
            }
            None => {
                let o = &self.landmarks.observations[k - self.edges.len()];
                let l = self.num_poses() + o.landmark;
                if u == l { o.pose } else { l }
            }
        }
    }

    /// Connected components through edges and landmark observations (two poses that observe
    /// one landmark are connected): the component label of every pose, labels numbered in
    /// order of each component's smallest id, and the number of components. Landmarks seen by
    /// no pose belong to no component ([`PoseGraph::landmark_components`]).
    pub fn connected_components(&self) -> (Vec<usize>, usize) {
        let (mut label, count) = self.node_components();
        label.truncate(self.num_poses());
        (label, count)
    }

    /// The component label of every landmark (as [`PoseGraph::connected_components`] numbers
    /// them), `None` for a landmark seen by no pose.
    pub fn landmark_components(&self) -> Vec<Option<usize>> {
        let (label, _) = self.node_components();
        label[self.num_poses()..]
            .iter()
            .map(|&c| (c != usize::MAX).then_some(c))
            .collect()
    }

    /// Labels of all nodes (poses, then landmarks; `usize::MAX` for unobserved landmarks).
    fn node_components(&self) -> (Vec<usize>, usize) {
        let (start, adj) = self.incidence();
        let n = self.num_poses();
        let mut label = vec![usize::MAX; n + self.landmarks.len()];
        let mut count = 0;
        let mut stack = Vec::new();
        for root in 0..n {
            if label[root] != usize::MAX {
                continue;
            }
            label[root] = count;
            stack.push(root);
            while let Some(u) = stack.pop() {
                for &k in &adj[start[u]..start[u + 1]] {
                    let v = self.other_end(k, u);
                    if label[v] == usize::MAX {
                        label[v] = count;
                        stack.push(v);
                    }
                }
            }
            count += 1;
        }
        (label, count)
    }

    /// The connected components as separate graphs (the paper's remark after Assumption 1: a
    /// graph with k components is k independent problems), with, for each, the dense indices
    /// of its poses in `self` (ascending) and of its edges (input order). FIX ids go with their
    /// component, and so do the landmarks its poses observe (with their observations, in input
    /// order); landmarks seen by no pose are in no component. A graph that is one component,
    /// every landmark observed, is its own: borrowed, not copied (at 10⁶ planar poses the copy
    /// was 125 MB).
    pub fn components(&self) -> Vec<(Cow<'_, PoseGraph>, Vec<usize>, Vec<usize>)> {
        let (label, count) = self.node_components();
        if count == 1 && label.iter().all(|&c| c == 0) {
            return vec![(
                Cow::Borrowed(self),
                (0..self.num_poses()).collect(),
                (0..self.edges.len()).collect(),
            )];
        }
        let n = self.num_poses();
        let mut poses: Vec<Vec<usize>> = vec![Vec::new(); count];
        for (k, &c) in label[..n].iter().enumerate() {
            poses[c].push(k);
        }
        let mut local = vec![0usize; n];
        for members in &poses {
            for (a, &k) in members.iter().enumerate() {
                local[k] = a;
            }
        }
        let mut landmarks: Vec<Vec<usize>> = vec![Vec::new(); count];
        let mut local_landmark = vec![0usize; self.landmarks.len()];
        for (k, &c) in label[n..].iter().enumerate() {
            if c != usize::MAX {
                local_landmark[k] = landmarks[c].len();
                landmarks[c].push(k);
            }
        }
        let mut observations: Vec<Vec<usize>> = vec![Vec::new(); count];
        for (k, o) in self.landmarks.observations.iter().enumerate() {
            observations[label[o.pose]].push(k);
        }
        let mut edges: Vec<Vec<usize>> = vec![Vec::new(); count];
        for (k, e) in self.edges.iter().enumerate() {
            edges[label[e.i]].push(k);
        }
        poses
            .into_iter()
            .zip(edges)
            .zip(landmarks.into_iter().zip(observations))
            .enumerate()
            .map(|(c, ((members, edge_ids), (marks, seen)))| {
                let graph = PoseGraph {
                    ids: members.iter().map(|&k| self.ids[k]).collect(),
                    poses: members.iter().map(|&k| self.poses[k]).collect(),
                    edges: edge_ids
                        .iter()
                        .map(|&k| {
                            let e = self.edges[k];
                            Edge {
                                i: local[e.i],
                                j: local[e.j],
                                ..e
                            }
                        })
                        .collect(),
                    fixed: self
                        .fixed
                        .iter()
                        .filter(|&&k| label[k] == c)
                        .map(|&k| local[k])
                        .collect(),
                    vertices_declared: self.vertices_declared,
                    noise: self.noise,
                    landmarks: Landmarks {
                        ids: marks.iter().map(|&k| self.landmarks.ids[k]).collect(),
                        positions: marks.iter().map(|&k| self.landmarks.positions[k]).collect(),
                        observations: seen
                            .iter()
                            .map(|&k| {
                                let o = self.landmarks.observations[k];
                                Observation {
                                    pose: local[o.pose],
                                    landmark: local_landmark[o.landmark],
                                    ..o
                                }
                            })
                            .collect(),
                        declared: self.landmarks.declared,
                        form: self.landmarks.form,
                    },
                };
                (Cow::Owned(graph), members, edge_ids)
            })
            .collect()
    }

    /// Whether the graph is a forest: no cycles, parallel edges included (Prop. 1), counting
    /// landmarks as nodes and observations as links (a landmark seen twice closes a cycle).
    pub fn is_forest(&self) -> bool {
        let (_, count) = self.connected_components();
        let observed = self
            .landmarks
            .observation_counts()
            .iter()
            .filter(|&&c| c > 0)
            .count();
        self.edges.len() + self.landmarks.observations.len() + count == self.num_poses() + observed
    }

    /// Whether the measurements compose to the identity along every cycle (Definition 1), to
    /// within `tolerance` (metres and radians): the poses composed along a spanning tree then
    /// explain every edge.
    pub fn is_balanced(&self, tolerance: f64) -> bool {
        let mut tree = self.clone();
        tree.initialize_spanning_tree();
        self.edges.iter().all(|e| {
            let rel = tree.poses[e.i]
                .to_isometry()
                .inv_mul(&tree.poses[e.j].to_isometry());
            let d = e.measurement.to_isometry().inv_mul(&rel);
            d.translation.vector.norm() <= tolerance && d.rotation.angle().abs() <= tolerance
        }) && self.landmarks.observations.iter().all(|o| {
            let [x, y] = tree.landmarks.positions[o.landmark];
            let seen = tree.poses[o.pose]
                .to_isometry()
                .inverse_transform_point(&nalgebra::Point2::new(x, y));
            (seen.coords - Vector2::new(o.d[0], o.d[1])).norm() <= tolerance
        })
    }

    /// The graph without pose `k`, whose two edges (h → k) and (k → l) are replaced by their
    /// composition h → l: the node removal of Sec. 6 (Fig. 8(b)-(f)), which keeps the error
    /// accumulated along every cycle. `None` unless `k` has exactly those two edges.
    pub fn eliminate_pose(&self, k: usize) -> Option<PoseGraph> {
        if !self.landmarks.is_empty() {
            return None;
        }
        let incident: Vec<&Edge> = self.edges.iter().filter(|e| e.i == k || e.j == k).collect();
        let [into, out] = incident[..] else {
            return None;
        };
        let (into, out) = if into.j == k {
            (into, out)
        } else {
            (out, into)
        };
        if into.j != k || out.i != k {
            return None;
        }
        let composed =
            Pose2::from_isometry(&(into.measurement.to_isometry() * out.measurement.to_isometry()));
        let at = |v: usize| if v > k { v - 1 } else { v };
        let mut edges: Vec<Edge> = self
            .edges
            .iter()
            .filter(|e| e.i != k && e.j != k)
            .map(|e| Edge {
                i: at(e.i),
                j: at(e.j),
                ..*e
            })
            .collect();
        edges.push(Edge {
            i: at(into.i),
            j: at(out.j),
            measurement: composed,
            noise: into.noise,
        });
        let keep = |v: &usize| *v != k;
        Some(PoseGraph {
            ids: (0..self.num_poses())
                .filter(keep)
                .map(|v| self.ids[v])
                .collect(),
            poses: (0..self.num_poses())
                .filter(keep)
                .map(|v| self.poses[v])
                .collect(),
            edges,
            fixed: self
                .fixed
                .iter()
                .filter(|v| keep(v))
                .map(|&v| at(v))
                .collect(),
            vertices_declared: self.vertices_declared,
            noise: self.noise,
            landmarks: Landmarks::default(),
        })
    }

    /// Initial poses composed along a breadth-first spanning tree of each component, rooted at
    /// the component's smallest id (placed at the origin): x_j = x_i · z for an edge i -> j met
    /// forwards, x_i = x_j · z⁻¹ met backwards. Neighbours are visited in input order (edges,
    /// then observations), so the result is deterministic. Landmarks are nodes of the tree too:
    /// l = p_i + R(θ_i) d from the pose that reaches it first, and a pose reached only through
    /// a landmark gets θ = 0 and p = l − d. Landmarks seen by no pose keep their positions.
    pub fn initialize_spanning_tree(&mut self) {
        let (start, adj) = self.incidence();
        let n = self.num_poses();
        let m = self.edges.len();
        let mut pose: Vec<Option<Isometry2<f64>>> = vec![None; n];
        let mut point: Vec<Option<Vector2<f64>>> = vec![None; self.landmarks.len()];
        let mut queue = std::collections::VecDeque::new();
        for root in 0..n {
            if pose[root].is_some() {
                continue;
            }
            pose[root] = Some(Isometry2::identity());
            queue.push_back(root);
            while let Some(u) = queue.pop_front() {
                if u >= n {
                    let l = point[u - n].expect("queued landmarks are set");
                    for &k in &adj[start[u]..start[u + 1]] {
                        let o = &self.landmarks.observations[k - m];
                        if pose[o.pose].is_none() {
                            let d = Vector2::new(o.d[0], o.d[1]);
                            pose[o.pose] = Some(Isometry2::new(l - d, 0.0));
                            queue.push_back(o.pose);
                        }
                    }
                    continue;
                }
                let xu = pose[u].expect("queued poses are set");
                for &k in &adj[start[u]..start[u + 1]] {
                    if k >= m {
                        let o = &self.landmarks.observations[k - m];
                        if point[o.landmark].is_none() {
                            let d = nalgebra::Point2::new(o.d[0], o.d[1]);
                            point[o.landmark] = Some((xu * d).coords);
                            queue.push_back(n + o.landmark);
                        }
                        continue;
                    }
                    // Composed only where the edge reaches a pose first (each edge is met from both
                    // ends, and most of them lead back into the tree).
                    let e = &self.edges[k];
                    let v = if e.i == u { e.j } else { e.i };
                    if pose[v].is_none() {
                        let z = e.measurement.to_isometry();
                        pose[v] = Some(if e.i == u { xu * z } else { xu * z.inverse() });
                        queue.push_back(v);
                    }
                }
            }
        }
        // In place: the poses' own memory, no fresh pages.
        self.poses.resize(n, Pose2::IDENTITY);
        for (at, p) in self.poses.iter_mut().zip(&pose) {
            *at = Pose2::from_isometry(&p.expect("every pose is reached from its root"));
        }
        if !self.landmarks.declared {
            for (at, p) in self.landmarks.positions.iter_mut().zip(point) {
                if let Some(p) = p {
                    *at = [p.x, p.y];
                }
            }
        }
    }

    /// Landmark positions from the poses: l = p_i + R(θ_i) d from each landmark's first
    /// observation in input order (landmarks seen by no pose keep theirs).
    pub fn initialize_landmarks(&mut self) {
        let mut done = vec![false; self.landmarks.len()];
        for o in &self.landmarks.observations {
            if !std::mem::replace(&mut done[o.landmark], true) {
                let p = self.poses[o.pose].to_isometry() * nalgebra::Point2::new(o.d[0], o.d[1]);
                self.landmarks.positions[o.landmark] = [p.x, p.y];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toro_order_matches_formats_md_3_1() {
        // A matrix with distinct entries m_rc = 10 r + c (upper triangle).
        let g2o = SymMat3([0.0, 1.0, 2.0, 11.0, 12.0, 22.0]);
        // TORO writes ff fs ss rr fr sr = m00 m01 m11 m22 m02 m12.
        assert_eq!(g2o.to_toro(), [0.0, 1.0, 11.0, 22.0, 2.0, 12.0]);
        assert_eq!(SymMat3::from_toro(g2o.to_toro()), g2o);
        // The diagonal example of docs/formats.md §3.1: g2o `a 0 0 b 0 c` is TORO `a 0 b c 0 0`.
        assert_eq!(
            SymMat3([3.0, 0.0, 0.0, 4.0, 0.0, 5.0]).to_toro(),
            [3.0, 0.0, 4.0, 5.0, 0.0, 0.0]
        );
    }

    #[test]
    fn positive_definiteness() {
        assert_eq!(SymMat3::IDENTITY.check_positive_definite(), Ok(()));
        // docs/formats.md §2.2's examples that g2o loads without complaint.
        assert_eq!(
            SymMat3([1.0, -2.0, 0.0, -1.0, 0.0, 1.0]).check_positive_definite(),
            Err(1)
        );
        assert_eq!(
            SymMat3([-1.0, 0.0, 0.0, 1.0, 0.0, 1.0]).check_positive_definite(),
            Err(0)
        );
        // Positive diagonal, but det([[1, 2], [2, 1]]) < 0.
        assert_eq!(
            SymMat3([1.0, 2.0, 0.0, 1.0, 0.0, 1.0]).check_positive_definite(),
            Err(1)
        );
        // Zero rotation information: positive semidefinite only.
        assert_eq!(
            SymMat3([1.0, 0.0, 0.0, 1.0, 0.0, 0.0]).check_positive_definite(),
            Err(2)
        );
    }

    #[test]
    fn inverse_of_diagonal() {
        let cov = SymMat3([0.01, 0.0, 0.0, 0.04, 0.0, 0.25]);
        let info = cov.inverse().unwrap();
        let expect = [100.0, 0.0, 0.0, 25.0, 0.0, 4.0];
        for (a, b) in info.0.iter().zip(expect) {
            assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "{a} vs {b}");
        }
    }

    fn graph(n: usize, edges: &[(usize, usize, Pose2)]) -> PoseGraph {
        PoseGraph {
            ids: (0..n as VertexId).collect(),
            poses: vec![Pose2::IDENTITY; n],
            edges: edges
                .iter()
                .map(|&(i, j, z)| Edge {
                    i,
                    j,
                    measurement: z,
                    noise: SymMat3::IDENTITY,
                })
                .collect(),
            fixed: vec![],
            vertices_declared: false,
            noise: NoiseKind::Information,
            landmarks: Landmarks::default(),
        }
    }

    #[test]
    fn spanning_tree_composes_forward_and_backward() {
        use std::f64::consts::FRAC_PI_2;
        // 0 -> 1: one metre ahead, turn left; edge written backwards 2 -> 1.
        let mut g = graph(
            3,
            &[
                (0, 1, Pose2::new(1.0, 0.0, FRAC_PI_2)),
                (2, 1, Pose2::new(0.0, -2.0, 0.0)),
            ],
        );
        g.initialize_spanning_tree();
        // By hand: x1 = (1, 0, π/2). x2 · (0, -2, 0) = x1, so x2 = x1 · (0, 2, 0) =
        // (1 + cos(π/2)·0 - sin(π/2)·2, 0 + sin(π/2)·0 + cos(π/2)·2, π/2) = (-1, 0, π/2).
        let p = &g.poses;
        assert_eq!(p[0], Pose2::IDENTITY);
        assert!((p[1].x - 1.0).abs() < 1e-15 && p[1].y.abs() < 1e-15);
        assert!((p[1].theta - FRAC_PI_2).abs() < 1e-15);
        assert!((p[2].x + 1.0).abs() < 1e-15 && p[2].y.abs() < 1e-15);
        assert!((p[2].theta - FRAC_PI_2).abs() < 1e-15);
    }

    #[test]
    fn components_split_and_keep_their_edges() {
        let mut g = graph(
            5,
            &[
                (0, 1, Pose2::new(1.0, 0.0, 0.0)),
                (3, 4, Pose2::new(2.0, 0.0, 0.0)),
                (1, 0, Pose2::new(-1.0, 0.0, 0.0)),
            ],
        );
        g.ids = vec![10, 11, 12, 13, 14];
        g.fixed = vec![3];
        let parts = g.components();
        assert_eq!(parts.len(), 3);
        let (a, poses, edges) = &parts[0];
        assert_eq!(
            (a.ids.clone(), poses.clone(), edges.clone()),
            (vec![10, 11], vec![0, 1], vec![0, 2])
        );
        assert_eq!((a.edges[1].i, a.edges[1].j), (1, 0));
        let (c, _, edges) = &parts[2];
        assert_eq!(
            (c.ids.clone(), edges.clone(), c.fixed.clone()),
            (vec![13, 14], vec![1], vec![0])
        );
        assert!(!g.is_forest()); // 0-1 twice: a cycle of parallel edges
        assert!(g.is_balanced(1e-12)); // but they agree
        g.edges[2].measurement.x = -1.5;
        assert!(!g.is_balanced(1e-12));
        g.edges.pop();
        assert!(g.is_forest());
    }

    /// A connected graph is its one component as it is (borrowed: the same graph, every pose and
    /// edge); a landmark no pose observes makes the component a copy without it.
    #[test]
    fn a_connected_graph_is_its_own_component() {
        let mut g = graph(
            3,
            &[
                (0, 1, Pose2::new(1.0, 0.0, 0.0)),
                (2, 1, Pose2::new(-1.0, 0.0, 0.0)),
            ],
        );
        g.landmarks = Landmarks {
            ids: vec![7, 9],
            positions: vec![[1.0, 2.0], [3.0, 4.0]],
            observations: vec![Observation {
                pose: 2,
                landmark: 0,
                d: [0.5, 0.5],
                information: SymMat2::IDENTITY,
            }],
            ..Default::default()
        };
        let mut seen = g.clone();
        seen.landmarks.observations.push(Observation {
            landmark: 1,
            ..seen.landmarks.observations[0]
        });
        let parts = seen.components();
        assert_eq!(parts.len(), 1);
        let (whole, poses, edges) = &parts[0];
        assert!(matches!(whole, Cow::Borrowed(b) if std::ptr::eq(*b, &seen)));
        assert_eq!((poses.clone(), edges.clone()), (vec![0, 1, 2], vec![0, 1]));
        let parts = g.components();
        assert_eq!(parts.len(), 1);
        let (copy, poses, edges) = &parts[0];
        assert!(matches!(copy, Cow::Owned(_)));
        assert_eq!((poses.clone(), edges.clone()), (vec![0, 1, 2], vec![0, 1]));
        assert_eq!(copy.landmarks.ids, vec![7]);
        assert_eq!(
            (copy.edges.clone(), copy.poses.clone()),
            (g.edges.clone(), g.poses.clone())
        );
    }

    #[test]
    fn components_count_isolated_poses() {
        let g = graph(5, &[(0, 1, Pose2::IDENTITY), (3, 4, Pose2::IDENTITY)]);
        let (label, count) = g.connected_components();
        assert_eq!(count, 3);
        assert_eq!(label, vec![0, 0, 1, 2, 2]);
    }
}
