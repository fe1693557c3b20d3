complete -c pgo-eval -l from -d 'Input format [default: from the extension (.g2o, .graph), else from the tags]' -r -f -a "g2o\t'g2o: `VERTEX_SE2`, `EDGE_SE2`, `FIX` (docs/formats.md §2)'
toro\t'TORO: `VERTEX2`/`VERTEX`, `EDGE2`/`EDGE` (docs/formats.md §3)'"
complete -c pgo-eval -l dialect -d 'How to read the six noise values of each edge [default: g2o for EDGE_SE2 tags, toro-info for EDGE2/EDGE tags]' -r -f -a "g2o\t'Information, g2o order `I11 I12 I13 I22 I23 I33` (g2o; GTSAM\'s readG2o)'
toro-info\t'Information, TORO order `ff fs ss rr fr sr` (TORO, HOG-Man)'
toro-cov\t'Covariance, TORO order (GTSAM\'s `.graph` files, read by `load2D` as covariances)'
g2o-cov\t'Covariance, g2o order'"
complete -c pgo-eval -l delta -d 'RPE: the step between the poses of a pair, in matched poses' -r
complete -c pgo-eval -l strict -d 'Treat unknown tags as errors instead of skipping them with a warning'
complete -c pgo-eval -l ignore-equiv -d 'Skip TORO\'s EQUIV lines (vertex merges, not implemented) with a warning instead of refusing the file: the graph is then the file\'s without them'
complete -c pgo-eval -l allow-indefinite -d 'Accept noise matrices that are not positive definite (the solvers take them only with --weights unit)'
complete -c pgo-eval -l all-pairs -d 'RPE: every pair (i, i + D), not only (0, D), (D, 2D), ...'
complete -c pgo-eval -l no-align -d 'Compare the positions as they are, without the SE(2) alignment'
complete -c pgo-eval -l json -d 'Print the report as one JSON object on stdout'
complete -c pgo-eval -s h -l help -d 'Print help (see more with \'--help\')'
complete -c pgo-eval -s V -l version -d 'Print version'
