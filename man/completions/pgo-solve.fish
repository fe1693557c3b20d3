complete -c pgo-solve -l from -d 'Input format [default: from the extension (.g2o, .graph), else from the tags]' -r -f -a "g2o\t'g2o: `VERTEX_SE2`, `EDGE_SE2`, `FIX` (docs/formats.md §2)'
toro\t'TORO: `VERTEX2`/`VERTEX`, `EDGE2`/`EDGE` (docs/formats.md §3)'"
complete -c pgo-solve -l dialect -d 'How to read the six noise values of each edge [default: g2o for EDGE_SE2 tags, toro-info for EDGE2/EDGE tags]' -r -f -a "g2o\t'Information, g2o order `I11 I12 I13 I22 I23 I33` (g2o; GTSAM\'s readG2o)'
toro-info\t'Information, TORO order `ff fs ss rr fr sr` (TORO, HOG-Man)'
toro-cov\t'Covariance, TORO order (GTSAM\'s `.graph` files, read by `load2D` as covariances)'
g2o-cov\t'Covariance, g2o order'"
complete -c pgo-solve -s o -l output -d 'Write the optimized graph here (- for stdout); with --json the graph goes only here' -r
complete -c pgo-solve -l to -d 'Output format [default: from the output\'s extension, else the input format]' -r -f -a "g2o\t'g2o: `VERTEX_SE2`, `EDGE_SE2`, `FIX` (docs/formats.md §2)'
toro\t'TORO: `VERTEX2`/`VERTEX`, `EDGE2`/`EDGE` (docs/formats.md §3)'"
complete -c pgo-solve -l weights -d 'Edge weights: unit (the paper\'s cost (5)) or isotropic (tau = 2/tr(inv(Omega_tt)), kappa = 2 Omega_thth: the SE-Sync/CPL-SLAM objective)' -r -f -a "unit\t'τ = κ = 1: exactly the paper\'s cost (5)/(8)'
isotropic\t'τ = 2 / tr(Ω_tt⁻¹), κ = 2 Ω_θθ: the objective of SE-Sync and CPL-SLAM (their κ‖R_j − R_i R_ij‖²_F equals 2κ|r_j − r_i R_ij|² for planar rotations)'"
complete -c pgo-solve -l method -d 'Solution method [auto: sdp for components of at most 100 poses, else staircase; a tree (no loop closure) is composed, f* = 0]' -r -f -a "auto\t'sdp for components of at most 100 poses, staircase beyond; a tree composed (Prop. 1)'
sdp\t'Algorithm 1: dual SDP, SZEP, eigenvector scaling or null-space method (dense; up to 2000 poses)'
staircase\t'The scalable solver: Riemannian Newton, sparse certificate, Riemannian staircase'"
complete -c pgo-solve -l solver -d 'SDP solver for the dual, on the components the sdp method solves (a warning if none) [default: ipm]' -r -f -a "ipm\t'The dedicated primal-dual interior-point method (default build)'
clarabel\t'clarabel on the real embedding of the Hermitian cone (cargo feature `clarabel-sdp`)'"
complete -c pgo-solve -l tol -d 'Relative suboptimality bound under which the result is called certified' -r
complete -c pgo-solve -l max-rank -d 'The staircase\'s largest rank: where the certificate fails at rank 1, the scalable solver lifts the estimate to ranks 2..P (docs/method.md §3.2); a larger P can find better estimates and tighter bounds where the relaxation is not exact, at a cost that grows as P³ per Newton step' -r
complete -c pgo-solve -l staircase-budget -d 'The staircase\'s work at most, in 10⁹ multiply-adds of its sparse factorizations (Newton steps, certificate attempts), counted from the factors\' structure and not timed, so the answer is the same on every machine; about 20 per second on one core. The first descent at rank 1 may always take 12 Newton steps. Past it the solver reports the best estimate and bound it reached and why it stopped. Graphs of a few hundred poses never reach the default; long false loop closures (outliers) fill the factors and reach it in seconds (try --robust)' -r
complete -c pgo-solve -l robust -d 'Robust estimation against false loop closures by graduated non-convexity with this loss (tls: truncated least squares, gm: Geman-McClure); see Robust below' -r -f -a "tls\t'Truncated least squares: rho(r) = min(r^2, c^2)'
gm\t'Geman-McClure: rho(r) = c^2 r^2 / (c^2 + r^2)'"
complete -c pgo-solve -l inlier-threshold -d 'With --robust: the inlier threshold c^2 on r_e^2 [default: 0.5 * chi2inv(0.99, 3) = 5.672, GTSAM\'s]' -r
complete -c pgo-solve -l marginals -d 'With --refine: write each pose\'s marginal covariance at the refined estimate here, one line per pose sorted by id, `id c11 c12 c13 c22 c23 c33` (the upper triangle over GTSAM\'s Pose2 tangent [x, y, theta], body frame, right Expmap), after a `#` comment line; the inverse of J^T Omega J over GTSAM\'s BetweenFactor<Pose2> Jacobians and the files\' information matrices, the held poses (FIX, else each component\'s first) zero. What GTSAM\'s Marginals gives with a tight prior on the held poses. Graphs with landmarks are refused' -r
complete -c pgo-solve -l rerun-save -d 'Write a rerun recording of the run to this .rrd file (poses, edges, residuals, solver iterations, eigenvalues, certificate); open it with `rerun PATH.rrd`' -r
complete -c pgo-solve -l rerun-connect -d 'Stream the recording to a running rerun viewer, at URL if given [default: rerun+http://127.0.0.1:9876/proxy]; an unreachable viewer is a warning' -r
complete -c pgo-solve -l strict -d 'Treat unknown tags as errors instead of skipping them with a warning'
complete -c pgo-solve -l ignore-equiv -d 'Skip TORO\'s EQUIV lines (vertex merges, not implemented) with a warning instead of refusing the file: the graph is then the file\'s without them'
complete -c pgo-solve -l allow-indefinite -d 'Accept noise matrices that are not positive definite (the solvers take them only with --weights unit)'
complete -c pgo-solve -l refine -d 'Refine the certified estimate by Levenberg-Marquardt under the file\'s full information matrices (g2o\'s chi2; on SE(3)^n for 3D g2o graphs) before writing it; the report\'s cost and bound stay those of the certified estimate, chi2 before and after is added, and the report says that the written estimate is the refined one, which is not certified (check it with pgo-certify)'
complete -c pgo-solve -l all-edges-uncertain -d 'With --robust: odometry edges (consecutive ids) may be rejected too (by default they are known inliers)'
complete -c pgo-solve -l warm-start -d 'With --robust: start each GNC inner problem after the first, and the inlier set\'s problem, from the previous iteration\'s estimate instead of the chordal initialization (slower, and worse inlier sets, on the benchmark files: see the README)'
complete -c pgo-solve -l certify-inner -d 'With --robust: certify each GNC inner problem for its weights too (by default only the inlier set\'s problem is certified: GNC uses the inner estimates, not their certificates, which took 30% of the run on intel.g2o with 100 false loop closures)'
complete -c pgo-solve -l drop-outliers -d 'With --robust: write the estimate without the rejected edges (by default -o holds every edge as read)'
complete -c pgo-solve -l fail-uncertified -d 'Exit with status 1 when the result is not certified within --tol (the estimate is still written); without it, status 0 either way'
complete -c pgo-solve -l json -d 'Print the report as one JSON object on stdout (the graph then goes only to -o)'
complete -c pgo-solve -l no-timings -d 'Leave the timings out of the report (for byte-identical output)'
complete -c pgo-solve -s q -l quiet -d 'No progress display (shown on stderr only when stderr is a terminal)'
complete -c pgo-solve -l progress -d 'Show the progress even when stderr is not a terminal, as plain lines (for logs)'
complete -c pgo-solve -l rerun-spawn -d 'Start a rerun viewer (the `rerun` executable on PATH, e.g. from PyPI rerun-sdk==0.36.3) and stream the recording to it'
complete -c pgo-solve -s h -l help -d 'Print help (see more with \'--help\')'
complete -c pgo-solve -s V -l version -d 'Print version'
