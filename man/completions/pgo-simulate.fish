complete -c pgo-simulate -l world -d 'The world: planar (the paper\'s model (47)), or an SE(3) world written as g2o 3D (see 3D worlds below)' -r -f -a "planar\t'Planar poses by the paper\'s model (47)'
sphere\t'SE(3) poses on rings of latitude of a sphere (like sphere2500)'
torus\t'SE(3) poses on rings around a torus (like torus3D)'
grid\t'SE(3) poses walking a cubic lattice (like grid3D)'"
complete -c pgo-simulate -s n -l poses -d 'Number of poses (ids 0..N-1)' -r
complete -c pgo-simulate -l loop-probability -d 'Probability P_c of a loop closure between two poses i < j with j > i + 1, each pair independently (per pose with --loop-model per-pose; in a 3D world each candidate) [default: 0.1, 1 in a 3D world]' -r
complete -c pgo-simulate -l loop-model -d 'Which loop closures are drawn (planar) [default: pairs]' -r -f -a "pairs\t'The paper\'s model (47): every pair (i, j), j > i + 1, with probability P_c (about P_c n^2/2 loop closures: for small n)'
per-pose\t'Each pose j >= 2 with probability P_c closes one loop to an earlier pose drawn uniformly (about P_c n loop closures: linear in n)'"
complete -c pgo-simulate -l rotation-noise -d 'Rotation noise e_R: gaussian:SIGMA (normal, standard deviation SIGMA radians) or uniform (uniform in (-pi, pi])' -r
complete -c pgo-simulate -l translation-noise -d 'Translation noise e_Delta: gaussian:SIGMA (normal in each coordinate, standard deviation SIGMA metres) or uniform:HALFWIDTH (uniform in [-HALFWIDTH, HALFWIDTH]^2)' -r
complete -c pgo-simulate -l seed -d 'Seed of the random number generator (any 64-bit unsigned integer)' -r
complete -c pgo-simulate -l side -d 'Side L of the square the positions are drawn from, in metres' -r
complete -c pgo-simulate -l landmarks -d 'Landmarks M: positions uniform in the square, observed (d = R_i^T (l - p_i) + e, e the translation noise) from every pose within --landmark-range; written as VERTEX_XY (ids N, N+1, ..., the landmarks some pose sees) and EDGE_SE2_XY lines' -r
complete -c pgo-simulate -l landmark-range -d 'A pose observes the landmarks within this distance, in metres' -r
complete -c pgo-simulate -s o -l output -d 'Output file, or - for stdout' -r
complete -c pgo-simulate -l to -d 'Output format [default: from the output\'s extension (.g2o, .graph), else g2o]' -r -f -a "g2o\t'g2o: `VERTEX_SE2`, `EDGE_SE2`, `FIX` (docs/formats.md §2)'
toro\t'TORO: `VERTEX2`/`VERTEX`, `EDGE2`/`EDGE` (docs/formats.md §3)'"
complete -c pgo-simulate -l corrupt -d 'Add false loop closures to this graph (- for stdin) instead of generating one (see Outliers below)' -r
complete -c pgo-simulate -l outliers -d 'Number of outlier groups to add to --corrupt\'s graph' -r
complete -c pgo-simulate -l outlier-model -d 'Which pose pairs outliers join: random (any two poses) or local (at most 20 ids apart)' -r -f -a "random\t'Any two poses, uniformly'
local\t'Poses at most 20 ids apart'"
complete -c pgo-simulate -l group -d 'Outliers per group: G consecutive pairs (v1+k, v2+k) sharing one measurement' -r
complete -c pgo-simulate -l outlier-list -d 'Write the list of the added outliers here: one line \'LINE I J\' each' -r
complete -c pgo-simulate -l rerun-save -d 'Write a rerun recording of the run to this .rrd file (poses, edges, residuals, solver iterations, eigenvalues, certificate); open it with `rerun PATH.rrd`' -r
complete -c pgo-simulate -l rerun-connect -d 'Stream the recording to a running rerun viewer, at URL if given [default: rerun+http://127.0.0.1:9876/proxy]; an unreachable viewer is a warning' -r
complete -c pgo-simulate -l force -d 'Generate however many loop closures the pairs model makes (see Size below)'
complete -c pgo-simulate -s q -l quiet -d 'Do not print the summary line on stderr'
complete -c pgo-simulate -l rerun-spawn -d 'Start a rerun viewer (the `rerun` executable on PATH, e.g. from PyPI rerun-sdk==0.36.3) and stream the recording to it'
complete -c pgo-simulate -s h -l help -d 'Print help (see more with \'--help\')'
complete -c pgo-simulate -s V -l version -d 'Print version'
