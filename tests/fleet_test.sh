#!/usr/bin/env bash
# lmcal fleet end to end, as a cluster user runs it: a generated fleet calibrated once as the
# reference; killed midway and resumed (the same summary, finished sets not made again, no
# stray temporary files); on MPI with 2 and 3 ranks (the same bytes); bad layouts refused
# before any work. $LMCAL is the binary; $LMCAL_MPI=1 when it was built with MPI.
set -uo pipefail
SOURCE=$(cd "$(dirname "$0")/.." && pwd)
source "$SOURCE/tests/support/checks.sh"
same_summary() {  # same_summary DIR: fleet.json, fleet.csv, fleet.html equal the reference's
  for f in fleet.json fleet.csv fleet.html; do cmp -s "ref/$f" "$1/$f" || { echo "  $1/$f differs"; return 1; }; done
}

"$LMCAL" generate fleet -o fleet --outlier 9:mu_st=1.4 --outlier 21:mu_v=1.5 --drift 2:mu_v=0.25 --corrupt 30 >/dev/null
"$LMCAL" fleet fleet -o ref --jobs 2 >ref.txt 2>&1
check "the reference run succeeds" test -s ref/fleet.json
check "the outliers are named" grep -q "outlier: u09: mu_st" ref.txt
check "the second outlier is named" grep -q "outlier: u21: mu_v" ref.txt
check "the drift is named" grep -q "drift: u02: mu_v" ref.txt
check "the corrupt set is reported" grep -q "failed u30: fleet/u30/friction.csv:" ref.txt
# fleet.html in a real browser: loads without errors, a forest plot and a drift plot per constant draw.
check "fleet.html loads and its 16 plots draw" bash "$SOURCE/tests/report_render_test.sh" "$work/ref/fleet.html" 16

# --- killed midway, resumed --------------------------------------------------------------------
"$LMCAL" fleet fleet -o killed --jobs 2 >/dev/null 2>&1 &
pid=$!
for _ in $(seq 600); do
  [[ $(find killed -name fleet_set.json 2>/dev/null | wc -l) -ge 20 ]] && break
  sleep 0.05
done
kill -9 "$pid" 2>/dev/null
wait "$pid" 2>/dev/null
find killed -name fleet_set.json | sort >done_before.txt
done_count=$(wc -l <done_before.txt)
check "the kill came midway ($done_count sets done)" test "$done_count" -ge 20 -a "$done_count" -lt 68
for f in $(cat done_before.txt); do stat -c '%n %Y %i' "$f"; done >stamps_before.txt
"$LMCAL" fleet fleet -o killed --jobs 2 >resumed.txt 2>&1
skipped=$(sed -n 's/.* \([0-9]*\) up to date.*/\1/p' resumed.txt)
check "the resumed run skips the finished sets ($skipped of $done_count)" test "${skipped:-0}" -ge "$done_count"
for f in $(cat done_before.txt); do stat -c '%n %Y %i' "$f"; done >stamps_after.txt
check "finished sets are not made again" cmp -s stamps_before.txt stamps_after.txt
check "the resumed summary is the reference's" same_summary killed
check "no temporary file is left" test -z "$(find killed -name '*.tmp')"

# --- MPI: the same bytes with 2 and 3 ranks --------------------------------------------------
if [[ "${LMCAL_MPI:-0}" == 1 ]]; then
  mpi_flags=(--oversubscribe)
  [[ $(id -u) -eq 0 ]] && mpi_flags+=(--allow-run-as-root)
  for np in 2 3; do
    mpirun "${mpi_flags[@]}" -np $np "$LMCAL" fleet fleet -o mpi$np >mpi$np.txt 2>&1
    check "mpirun -np $np succeeds" test $? -eq 0
    check "mpirun -np $np gives the reference's summary" same_summary mpi$np
    check "mpirun -np $np calibrated every set once" grep -q "68 calibrated, 0 up to date" mpi$np.txt
  done
else
  echo "note: lmcal was built without MPI; the mpirun checks were skipped"
fi

# --- the documented Slurm job array: two array tasks, then the summary ------------------------
for task in 0 1; do
  FLEET=fleet OUT=array LMCAL="$LMCAL" SLURM_ARRAY_TASK_ID=$task SLURM_ARRAY_TASK_COUNT=2 \
    bash "$SOURCE/examples/slurm/fleet_array.sbatch" >array$task.txt 2>&1
  check "array task $task succeeds" test $? -eq 0
done
"$LMCAL" fleet fleet -o array --summarize >/dev/null 2>&1
check "the job array's summary is the reference's" same_summary array

# --- bad layouts: refused before any work, naming the entry --------------------------------
mkdir -p empty/a
check "a root without measurement folders is refused" refused "no measurement folders" fleet empty -o out
mkdir -p listed/a && cp fleet/u05/friction.csv listed/a/
printf '[[set]]\nfolder = "a"\n[[set]]\nfolder = "b"\n' >listed/fleet.toml
check "a fleet.toml naming a missing folder is refused" refused "listed/fleet.toml:4:10: folder listed/b does not exist" fleet listed -o out
mkdir -p listed/b && cp fleet/u05/friction.csv listed/b/
printf '[[set]]\nfolder = "a"\nunit = "7"\n[[set]]\nfolder = "b"\nunit = "7"\n' >listed/fleet.toml
check "duplicate unit and date are refused" refused "unit 7 has two sets dated ''" fleet listed -o out
check "a bad shard is refused" refused "--shard" fleet fleet --shard 2/2 -o out
check "--summarize with --shard is refused" refused "--summarize" fleet fleet --shard 0/2 --summarize -o out
check "--summarize without results names what is missing" refused "68 of 68 sets have no up-to-date results" fleet fleet --summarize -o out

# --- a hostile fleet.toml: it cannot read, write into or delete a sibling folder ------------
# The sibling: a set calibrated into its own folder (model.toml, report.html, … beside the logs).
mkdir -p sibling/unit && cp fleet/u05/friction.csv sibling/unit/
"$LMCAL" calibrate sibling/unit -o sibling/unit >/dev/null 2>&1
check "the sibling holds its results" test -s sibling/unit/model.toml -a -s sibling/unit/report.html
snapshot() { (cd sibling && find . -type f -print0 | sort -z | xargs -0 sha256sum); }
snapshot >sibling_before.txt
mkdir -p hostile/own && printf 'not,a,log\n1,2\n' >hostile/own/friction.csv   # a set that fails
printf '[[set]]\nfolder = "own"\n[[set]]\nfolder = "../sibling/unit"\n' >hostile/fleet.toml
check "a fleet.toml folder outside ROOT is refused at its line" \
  refused "hostile/fleet.toml:4:10: folder '../sibling/unit' is outside hostile" fleet hostile -o out
printf '[[set]]\nfolder = "%s/sibling/unit"\n' "$work" >hostile/fleet.toml
check "an absolute folder outside ROOT is refused" refused "is outside hostile" fleet hostile -o out
ln -s ../sibling/unit hostile/link
printf '[[set]]\nfolder = "link"\n' >hostile/fleet.toml
check "a link out of ROOT is refused" refused "through a symbolic link" fleet hostile -o out
rm hostile/fleet.toml
check "found by the walk, too" refused "hostile/link: this folder is outside hostile" fleet hostile -o out
rm hostile/link
# A set's manifest naming the sibling's log, and a log that links to /etc/passwd: the set fails,
# and the record says why without a byte of either file.
mkdir -p hostile/reader && printf 'file = "../../sibling/unit/friction.csv"\n' >hostile/reader/friction.toml
mkdir -p hostile/linker && ln -s /etc/passwd hostile/linker/friction.csv
# -o such that OUT/own is a folder of the sibling's: its files are not this set's to remove.
mkdir -p victim/own && cp sibling/unit/model.toml sibling/unit/report.html victim/own/
"$LMCAL" fleet hostile -o victim >hostile.txt 2>&1
check "the hostile sets fail and the fleet finishes" grep -q "3 sets: 3 calibrated, 0 up to date (skipped), 3 failed" hostile.txt
check "the manifest's file outside its folder is refused" \
  grep -q "friction.toml:1:8: file '../../sibling/unit/friction.csv' is outside" victim/reader/fleet_set.json
check "the link to /etc/passwd is refused, not read" grep -q "linker/friction.csv: is outside hostile through a symbolic link" victim/linker/fleet_set.json
check "no content of /etc/passwd in any output" bash -c '! grep -rq "root:" victim'
check "OUT/own's files, not written by this set, stay" cmp -s victim/own/model.toml sibling/unit/model.toml
snapshot >sibling_after.txt
check "the sibling is byte-identical afterwards" cmp -s sibling_before.txt sibling_after.txt
# With --allow-outside-root the sibling is read, and its outputs still go under -o.
printf '[[set]]\nfolder = "../sibling/unit"\n' >hostile/fleet.toml
"$LMCAL" --allow-outside-root fleet hostile -o allowed >/dev/null 2>&1
check "--allow-outside-root reads it, writing under OUT/outside/…" test -s "allowed/outside$(cd sibling/unit && pwd -P)/model.toml"
snapshot >sibling_after.txt
check "and the sibling is still byte-identical" cmp -s sibling_before.txt sibling_after.txt
check "an output folder that cannot be made is refused before any work" refused "fleet.toml is not a folder" fleet hostile -o hostile/fleet.toml/out

finish fleet_test.sh
