#!/usr/bin/env bash
# Launched by mpirun: runs the command and leaves this rank's exit code and stderr in DIR, so that a test
# can check every rank, not only what rank 0 printed. Usage: each_rank.sh DIR COMMAND [ARGS...]
dir=$1; shift
rank=${OMPI_COMM_WORLD_RANK:-${PMI_RANK:-0}}
"$@" 2> "$dir/rank$rank.err.tmp"
code=$?
cat "$dir/rank$rank.err.tmp" >&2
mv "$dir/rank$rank.err.tmp" "$dir/rank$rank.err"
echo "$code" > "$dir/rank$rank.code"
exit "$code"
