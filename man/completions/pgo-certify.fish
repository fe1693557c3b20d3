complete -c pgo-certify -l from -d 'Input format [default: from the extension (.g2o, .graph), else from the tags]' -r -f -a "g2o\t'g2o: `VERTEX_SE2`, `EDGE_SE2`, `FIX` (docs/formats.md §2)'
toro\t'TORO: `VERTEX2`/`VERTEX`, `EDGE2`/`EDGE` (docs/formats.md §3)'"
complete -c pgo-certify -l dialect -d 'How to read the six noise values of each edge [default: g2o for EDGE_SE2 tags, toro-info for EDGE2/EDGE tags]' -r -f -a "g2o\t'Information, g2o order `I11 I12 I13 I22 I23 I33` (g2o; GTSAM\'s readG2o)'
toro-info\t'Information, TORO order `ff fs ss rr fr sr` (TORO, HOG-Man)'
toro-cov\t'Covariance, TORO order (GTSAM\'s `.graph` files, read by `load2D` as covariances)'
g2o-cov\t'Covariance, g2o order'"
complete -c pgo-certify -l estimate -d 'The estimate: a g2o or TORO file whose vertex lines hold the poses, by id [default: the graph file\'s own vertices]' -r
complete -c pgo-certify -l weights -d 'Edge weights: unit (the paper\'s cost (5)) or isotropic (tau = 2/tr(inv(Omega_tt)), kappa = 2 Omega_thth: the SE-Sync/CPL-SLAM objective)' -r -f -a "unit\t'τ = κ = 1: exactly the paper\'s cost (5)/(8)'
isotropic\t'τ = 2 / tr(Ω_tt⁻¹), κ = 2 Ω_θθ: the objective of SE-Sync and CPL-SLAM (their κ‖R_j − R_i R_ij‖²_F equals 2κ|r_j − r_i R_ij|² for planar rotations)'"
complete -c pgo-certify -l tol -d 'Relative suboptimality bound under which the estimate is called certified' -r
complete -c pgo-certify -l rerun-save -d 'Write a rerun recording of the run to this .rrd file (poses, edges, residuals, solver iterations, eigenvalues, certificate); open it with `rerun PATH.rrd`' -r
complete -c pgo-certify -l rerun-connect -d 'Stream the recording to a running rerun viewer, at URL if given [default: rerun+http://127.0.0.1:9876/proxy]; an unreachable viewer is a warning' -r
complete -c pgo-certify -l strict -d 'Treat unknown tags as errors instead of skipping them with a warning'
complete -c pgo-certify -l ignore-equiv -d 'Skip TORO\'s EQUIV lines (vertex merges, not implemented) with a warning instead of refusing the file: the graph is then the file\'s without them'
complete -c pgo-certify -l allow-indefinite -d 'Accept noise matrices that are not positive definite (the solvers take them only with --weights unit)'
complete -c pgo-certify -l json -d 'Print the report as one JSON object on stdout'
complete -c pgo-certify -s q -l quiet -d 'No progress display (shown on stderr only when stderr is a terminal)'
complete -c pgo-certify -l progress -d 'Show the progress even when stderr is not a terminal, as plain lines (for logs)'
complete -c pgo-certify -l rerun-spawn -d 'Start a rerun viewer (the `rerun` executable on PATH, e.g. from PyPI rerun-sdk==0.36.3) and stream the recording to it'
complete -c pgo-certify -s h -l help -d 'Print help (see more with \'--help\')'
complete -c pgo-certify -s V -l version -d 'Print version'
