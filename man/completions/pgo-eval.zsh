#compdef pgo-eval

autoload -U is-at-least

_pgo-eval() {
    typeset -A opt_args
    typeset -a _arguments_options
    local ret=1

    if is-at-least 5.2; then
        _arguments_options=(-s -S -C)
    else
        _arguments_options=(-s -C)
    fi

    local context curcontext="$curcontext" state line
    _arguments "${_arguments_options[@]}" : \
'--from=[Input format \[default\: from the extension (.g2o, .graph), else from the tags\]]:FORMAT:((g2o\:"g2o\: \`VERTEX_SE2\`, \`EDGE_SE2\`, \`FIX\` (docs/formats.md §2)"
toro\:"TORO\: \`VERTEX2\`/\`VERTEX\`, \`EDGE2\`/\`EDGE\` (docs/formats.md §3)"))' \
'--dialect=[How to read the six noise values of each edge \[default\: g2o for EDGE_SE2 tags, toro-info for EDGE2/EDGE tags\]]:DIALECT:((g2o\:"Information, g2o order \`I11 I12 I13 I22 I23 I33\` (g2o; GTSAM'\''s readG2o)"
toro-info\:"Information, TORO order \`ff fs ss rr fr sr\` (TORO, HOG-Man)"
toro-cov\:"Covariance, TORO order (GTSAM'\''s \`.graph\` files, read by \`load2D\` as covariances)"
g2o-cov\:"Covariance, g2o order"))' \
'--delta=[RPE\: the step between the poses of a pair, in matched poses]:D:_default' \
'--strict[Treat unknown tags as errors instead of skipping them with a warning]' \
'(--strict)--ignore-equiv[Skip TORO'\''s EQUIV lines (vertex merges, not implemented) with a warning instead of refusing the file\: the graph is then the file'\''s without them]' \
'--allow-indefinite[Accept noise matrices that are not positive definite (the solvers take them only with --weights unit)]' \
'--all-pairs[RPE\: every pair (i, i + D), not only (0, D), (D, 2D), ...]' \
'--no-align[Compare the positions as they are, without the SE(2) alignment]' \
'--json[Print the report as one JSON object on stdout]' \
'-h[Print help (see more with '\''--help'\'')]' \
'--help[Print help (see more with '\''--help'\'')]' \
'-V[Print version]' \
'--version[Print version]' \
':estimate -- The estimate\: a g2o or TORO file whose vertex lines hold the poses:_default' \
':reference -- The reference (ground truth)\: a g2o or TORO file whose vertex lines hold the poses:_default' \
&& ret=0
}

(( $+functions[_pgo-eval_commands] )) ||
_pgo-eval_commands() {
    local commands; commands=()
    _describe -t commands 'pgo-eval commands' commands "$@"
}

if [ "$funcstack[1]" = "_pgo-eval" ]; then
    _pgo-eval "$@"
else
    compdef _pgo-eval pgo-eval
fi
