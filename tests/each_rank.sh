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
# mpirun ends the other ranks as soon as one exits non-zero: a rank that exits first would have the
# others killed before they record their code (seen under load: "rank 1 left no exit code"). So no rank
# exits until every rank has recorded one, or 20 s have passed (a rank that hung or died stays missing).
size=${OMPI_COMM_WORLD_SIZE:-${PMI_SIZE:-1}}
for _ in $(seq 400); do
  [ "$(ls "$dir"/rank*.code 2>/dev/null | wc -l)" -ge "$size" ] && break
  sleep 0.05
done
exit "$code"
