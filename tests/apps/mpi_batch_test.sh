#!/usr/bin/env bash
# The batch over MPI ranks against the serial batch: `mpirun -n 3 isowave
# convert` and `isowave convert` over the same builtin fields of different
# sizes and one missing file must write the same files with the same bytes,
# report the same totals (rank 0's JSON, one object) and both exit with 1.
# Usage: mpi_batch_test.sh ISOWAVE MPIEXEC WORKDIR
set -euo pipefail
isowave="$1" mpiexec="$2" work="$3"
rm -rf "$work" && mkdir -p "$work" && cd "$work"
inputs=(builtin:sphere:24 builtin:torus:32 builtin:mixing:40 builtin:genus3:28 missing.nrrd)

status=0
"$isowave" convert "${inputs[@]}" --iso 0 --out-dir serial --json > serial.json 2> serial.log || status=$?
[ "$status" -eq 1 ] || { echo "serial run exited with $status, expected 1"; cat serial.log; exit 1; }
status=0
"$mpiexec" --oversubscribe --allow-run-as-root -n 3 "$isowave" convert "${inputs[@]}" --iso 0 --out-dir mpi --json \
  > mpi.json 2> mpi.log || status=$?
[ "$status" -eq 1 ] || { echo "mpirun exited with $status, expected 1"; cat mpi.log; exit 1; }

[ "$(ls serial)" = "$(ls mpi)" ] || { echo "different files: $(ls serial) against $(ls mpi)"; exit 1; }
[ "$(ls serial | wc -l)" -eq 4 ] || { echo "expected 4 files, got $(ls serial)"; exit 1; }
for f in serial/*; do cmp "$f" "mpi/$(basename "$f")"; done

# Totals and each job's outcome, in job order (the times differ).
/usr/bin/python3 -c '
import json, sys
def summary(path):
    d = json.load(open(path))
    return ({k: d[k] for k in ("inputs", "jobs", "converted", "failed", "volume_bytes", "bytes")},
            [(r["input"], r["ok"], r.get("bytes"), r.get("error")) for r in d["results"]])
serial, mpi = summary("serial.json"), summary("mpi.json")
assert serial[0] == {"inputs": 5, "jobs": 5, "converted": 4, "failed": 1, "volume_bytes": serial[0]["volume_bytes"],
                     "bytes": serial[0]["bytes"]}, serial[0]
assert serial == mpi, (serial, mpi)
'
# The failure reported once (on stderr, by the rank that ran it).
[ "$(grep -c 'missing.nrrd: cannot open' mpi.log)" -eq 1 ] || { echo "the failure not reported once"; cat mpi.log; exit 1; }
echo "mpi batch: same files, bytes and totals as the serial batch"
