_pgo__simulate() {
    local i cur prev opts cmd
    COMPREPLY=()
    if [[ "${BASH_VERSINFO[0]}" -ge 4 ]]; then
        cur="$2"
    else
        cur="${COMP_WORDS[COMP_CWORD]}"
    fi
    prev="$3"
    cmd=""
    opts=""

    for i in "${COMP_WORDS[@]:0:COMP_CWORD}"
    do
        case "${cmd},${i}" in
            ",$1")
                cmd="pgo__simulate"
                ;;
            *)
                ;;
        esac
    done

    case "${cmd}" in
        pgo__simulate)
            opts="-n -o -q -h -V --world --poses --loop-probability --loop-model --force --rotation-noise --translation-noise --seed --side --landmarks --landmark-range --output --to --quiet --corrupt --outliers --outlier-model --group --outlier-list --rerun-save --rerun-connect --rerun-spawn --help --version"
            if [[ ${cur} == -* || ${COMP_CWORD} -eq 1 ]] ; then
                COMPREPLY=( $(compgen -W "${opts}" -- "${cur}") )
                return 0
            fi
            case "${prev}" in
                --world)
                    COMPREPLY=($(compgen -W "planar sphere torus grid" -- "${cur}"))
                    return 0
                    ;;
                --poses)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                -n)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --loop-probability)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --loop-model)
                    COMPREPLY=($(compgen -W "pairs per-pose" -- "${cur}"))
                    return 0
                    ;;
                --rotation-noise)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --translation-noise)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --seed)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --side)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --landmarks)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --landmark-range)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --output)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                -o)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --to)
                    COMPREPLY=($(compgen -W "g2o toro" -- "${cur}"))
                    return 0
                    ;;
                --corrupt)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --outliers)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --outlier-model)
                    COMPREPLY=($(compgen -W "random local" -- "${cur}"))
                    return 0
                    ;;
                --group)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --outlier-list)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --rerun-save)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --rerun-connect)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                *)
                    COMPREPLY=()
                    ;;
            esac
            COMPREPLY=( $(compgen -W "${opts}" -- "${cur}") )
            return 0
            ;;
    esac
}

if [[ "${BASH_VERSINFO[0]}" -eq 4 && "${BASH_VERSINFO[1]}" -ge 4 || "${BASH_VERSINFO[0]}" -gt 4 ]]; then
    complete -F _pgo__simulate -o nosort -o bashdefault -o default pgo-simulate
else
    complete -F _pgo__simulate -o bashdefault -o default pgo-simulate
fi
