#!/usr/bin/env bash
# weaver-mpi under mpirun against the serial weaver (ctest: Tools.Mpi*).
# For 1 to 4 ranks and MPI's singleton start (no mpirun), on the basin at
# 0.2 and 0.5 Hz, loh1, a non-cube basin and a model database: the sharded
# octant table verifies, serial balance reads it to the serial run's table,
# and 'weaver compact' joins it to the serial construct's file byte for
# byte; balance on the ranks from the sharded leaves compacts to the serial
# balance's file; extract on the ranks from the balanced table gives a
# sharded node table that verifies and compacts to the serial extract's
# file.  Export of raw and pvtu parts, one a rank, as the serial export's
# files.  Then: more ranks than work (balance and extract too), ranks given
# different arguments, a database some rank cannot see, a sharded mesh that
# lost its MANIFEST (weaver recover), rank 1 and rank 0 (which commits)
# each killed at each of its durable steps and failing at three of them (the
# old database stays, byte for byte, or where rank 0 dies at its last step,
# after the commit's rename, the new one).
#
# usage: check_mpi.sh WEAVER WEAVER_MPI SCRATCH
set -euo pipefail
weaver=$(realpath "$1") mpi=$(realpath "$2") tmp=$3  # absolute: some ranks start elsewhere
rm -rf "$tmp" && mkdir -p "$tmp"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
# One host: shared memory and loopback only.  mpirun starts in 0.22 s instead
# of 0.5 s (no network transports probed), over a hundred times here.
export OMPI_MCA_pml=ob1 OMPI_MCA_btl=self,vader OMPI_MCA_btl_vader_single_copy_mechanism=none
run() { mpirun --oversubscribe -np "$@"; }
fail() { echo "FAIL: $*" >&2; exit 1; }
# on NP COMMAND...: weaver-mpi on NP ranks under mpirun, or alone (MPI's
# singleton start) for NP = 0.
on() { local np=$1; shift; if [ "$np" = 0 ]; then "$mpi" "$@"; else run "$np" "$mpi" "$@"; fi; }
table_md5() { md5sum "$1"/octants-*.bt | cut -d' ' -f1; }
# The MANIFEST and the files it names (leftovers of a failed writer aside).
live_md5() { (cd "$1" && md5sum MANIFEST $(awk '$1 == "table" || $1 == "shard" {print $3}' MANIFEST)); }

check_model() {  # name, construct options...
  local name=$1; shift
  local serial=$tmp/$name.serial want balanced nodes
  # A model database is named in the octants by its identity, not its path:
  # balance is told where it is.
  local balance_model=() prev=""
  for a in "$@"; do
    [ "$prev" = --model ] && [ "${a#db:}" != "$a" ] && balance_model=(--model "$a")
    prev=$a
  done
  "$weaver" construct "$serial" "$@" --quiet >/dev/null
  want=$(table_md5 "$serial")
  "$weaver" balance "$serial" "${balance_model[@]}" --quiet >/dev/null
  balanced=$(table_md5 "$serial")
  cp -r "$serial" "$serial.x"
  "$weaver" extract "$serial.x" --quiet >/dev/null
  nodes=$(md5sum "$serial.x"/nodes-*.bt | cut -d' ' -f1)
  for np in ${ranks:-0 1 2 3 4}; do
    local db=$tmp/$name.$np
    on "$np" construct "$db" "$@" --quiet >"$tmp/out" || fail "$name: -np $np construct"
    grep -q "^sharded " "$tmp/out" || fail "$name -np $np: no summary"
    "$weaver" verify "$db" >/dev/null || fail "$name -np $np: verify of the sharded table"
    "$weaver" stat "$db" >/dev/null || fail "$name -np $np: stat"
    cp -r "$db" "$db.b"
    cp -r "$db" "$db.mb"
    "$weaver" balance "$db.b" "${balance_model[@]}" --quiet >/dev/null
    [ "$(table_md5 "$db.b")" = "$balanced" ] || fail "$name -np $np: balance from shards differs"
    # Balance on the ranks, from the sharded leaves: the serial balance's table.
    on "$np" balance "$db.mb" "${balance_model[@]}" --quiet >"$tmp/out" ||
      fail "$name: -np $np balance"
    "$weaver" verify "$db.mb" >/dev/null || fail "$name -np $np: verify of the balanced shards"
    "$weaver" compact "$db.mb" >/dev/null
    [ "$(table_md5 "$db.mb")" = "$balanced" ] || fail "$name -np $np: balance on ranks differs"
    "$weaver" compact "$db" >/dev/null
    [ "$(table_md5 "$db")" = "$want" ] || fail "$name -np $np: compacted table differs"
    # Extract on the ranks from the balanced table: the serial node table.
    local x=$tmp/$name.x$np
    cp -r "$serial" "$x"
    on "$np" extract "$x" --quiet >"$tmp/out" || fail "$name: -np $np extract"
    "$weaver" verify "$x" >/dev/null || fail "$name -np $np: verify of the sharded node table"
    "$weaver" compact "$x" >/dev/null
    [ "$(md5sum "$x"/nodes-*.bt | cut -d' ' -f1)" = "$nodes" ] ||
      fail "$name -np $np: compacted node table differs"
    echo "ok  $name at $np ranks (0: singleton): octants compact to $want, nodes to $nodes"
  done
}

# Every command has --help; an unknown one is a usage error (exit 2).
"$mpi" --help >"$tmp/out" || fail "weaver-mpi --help"
for cmd in construct balance extract boundary mesh export; do
  grep -q "^  $cmd " "$tmp/out" || fail "weaver-mpi --help does not name $cmd"
  "$mpi" "$cmd" --help >"$tmp/help" && grep -q "usage:" "$tmp/help" || fail "weaver-mpi $cmd --help"
done
set +e
"$mpi" frobnicate >/dev/null 2>&1
code=$?
set -e
[ "$code" = 2 ] || fail "weaver-mpi frobnicate: exit $code"
echo "ok  --help and usage errors"

check_model basin02 --model basin --freq 0.2
# The basin at 0.5 Hz (11.4M leaves) on 1 to 4 ranks; the singleton start is
# the 0.2 Hz basin's.
ranks="1 2 3 4" check_model basin05 --model basin --freq 0.5

check_model loh1 --model loh1 --freq 1 --domain 30000,30000,15000
check_model slab --model basin --freq 0.2 --domain 100000,50000,12500
# A user's own model: a 1-D layered table imported into a model database,
# which every rank samples (weaver model import, then --model db:).
printf '0 1800 1000 2000\n500 4000 2300 2400\n3000 6000 3464 2700\n' >"$tmp/layers.txt"
"$weaver" model import "$tmp/layers.db" --from "layers:$tmp/layers.txt" >/dev/null
ranks="2 3" check_model layers --model "db:$tmp/layers.db" --freq 0.3 --domain 20000,20000,10000

# A mesh under a ground (a ridge across the box): the carved tables of 1 to
# 4 ranks, and the boundary table the ranks derive, compact to the serial
# mesh's, byte for byte.
{ printf 'ncols 11\nnrows 11\nxllcenter 0\nyllcenter 0\ncellsize 10000\n'
  for r in 0 1 2 3 4 5 6 7 8 9 10; do
    for c in 0 1 2 3 4 5 6 7 8 9 10; do printf '%d ' $(( 300 * (5 - (c > 5 ? c - 5 : 5 - c)) )); done
    printf '\n'
  done; } >"$tmp/ridge.asc"
"$weaver" mesh "$tmp/ground.serial" --model basin --freq 0.15 --surface "asc:$tmp/ridge.asc" \
  --quiet >/dev/null
for np in 1 2 3 4; do
  run "$np" "$mpi" mesh "$tmp/ground.$np" --model basin --freq 0.15 \
    --surface "asc:$tmp/ridge.asc" --quiet >"$tmp/out" || fail "ground mesh -np $np"
  grep -q "^carved " "$tmp/out" || fail "ground mesh -np $np: no carve in the summary"
  "$weaver" compact "$tmp/ground.$np" >/dev/null
  for t in octants nodes boundary; do
    [ "$(md5sum "$tmp/ground.$np"/$t-*.bt | cut -d' ' -f1)" = \
      "$(md5sum "$tmp/ground.serial"/$t-*.bt | cut -d' ' -f1)" ] ||
      fail "ground mesh -np $np: compacted $t differ from the serial mesh's"
  done
done
# weaver-mpi boundary alone, over the serial mesh (its octants one file).
cp -r "$tmp/ground.serial" "$tmp/ground.b"
run 3 "$mpi" boundary "$tmp/ground.b" >"$tmp/out" || fail "boundary -np 3"
grep -q "^boundary: [0-9]* faces in .* on 3 ranks" "$tmp/out" || fail "boundary: no summary"
"$weaver" compact "$tmp/ground.b" >/dev/null
[ "$(md5sum "$tmp/ground.b"/boundary-*.bt | cut -d' ' -f1)" = \
  "$(md5sum "$tmp/ground.serial"/boundary-*.bt | cut -d' ' -f1)" ] ||
  fail "weaver-mpi boundary on 3 ranks: the compacted table differs from the serial one"
echo "ok  a mesh under a ground on 1 to 4 ranks compacts to the serial tables, boundary included"

# mesh: the three stages on 3 ranks, both tables as the serial mesh's.
"$weaver" mesh "$tmp/mesh.serial" --model basin --freq 0.2 --quiet >/dev/null
run 3 "$mpi" mesh "$tmp/mesh" --model basin --freq 0.2 --quiet >"$tmp/out" || fail "mesh -np 3"
"$weaver" verify "$tmp/mesh" >/dev/null || fail "mesh: verify of the sharded mesh"
# A lost MANIFEST: weaver recover rebuilds both sharded tables from the
# ranks' files, and they compact to the serial mesh's.
cp -r "$tmp/mesh" "$tmp/mesh.lost" && rm "$tmp/mesh.lost/MANIFEST"
"$weaver" recover "$tmp/mesh.lost" >"$tmp/out" || fail "recover of the sharded mesh"
[ "$(grep -c 'shards)$' "$tmp/out")" = 3 ] || fail "recover: not the three tables from shards"
"$weaver" compact "$tmp/mesh.lost" >/dev/null
for t in octants nodes boundary; do
  [ "$(md5sum "$tmp/mesh.lost"/$t-*.bt | cut -d' ' -f1)" = \
    "$(md5sum "$tmp/mesh.serial"/$t-*.bt | cut -d' ' -f1)" ] || fail "recover: $t differ"
done
echo "ok  recover of a sharded mesh"
# Export on the ranks, one part a rank, from the shards: the serial export's
# files, byte for byte (raw parts by element runs and by a stored graph
# partition; pvtu pieces within a box).
export_parts() {  # name, np, db, serial db, suffix, export options...
  local name=$1 np=$2 db=$3 serial=$4 ext=$5; shift 5
  "$weaver" export "$serial" "$@" --parts "$np" --out "$tmp/$name.serial$ext" --quiet >/dev/null
  run "$np" "$mpi" export "$db" "$@" --out "$tmp/$name.mpi$ext" >"$tmp/out" || fail "export $name"
  grep -q "^export: $np parts" "$tmp/out" || fail "export $name: no summary"
}
# weaver-mpi mesh derived the boundary table too: each part's
# boundary_faces are the serial export's.
export_parts raw 3 "$tmp/mesh" "$tmp/mesh.serial" "" --format raw
diff -r "$tmp/raw.serial" "$tmp/raw.mpi" >/dev/null || fail "export raw on 3 ranks differs"
export_parts pvtu 3 "$tmp/mesh" "$tmp/mesh.serial" .pvtu --format pvtu --box 0,0,0,60000,40000,20000
for p in 0 1 2; do
  cmp -s "$tmp/pvtu.serial/pvtu.serial_$p.vtu" "$tmp/pvtu.mpi/pvtu.mpi_$p.vtu" ||
    fail "export pvtu piece $p on 3 ranks differs"
done
[ "$(grep -c '<Piece' "$tmp/pvtu.mpi.pvtu")" = 3 ] || fail "export pvtu: the index lacks pieces"
cp -r "$tmp/mesh.serial" "$tmp/mesh.graph"
"$weaver" partition "$tmp/mesh.graph" --parts 2 --method graph --quiet >/dev/null
export_parts graph 2 "$tmp/mesh.graph" "$tmp/mesh.graph" "" --format raw
diff -r "$tmp/graph.serial" "$tmp/graph.mpi" >/dev/null || fail "export raw by graph parts differs"
grep -q '"method": "graph"' "$tmp/graph.mpi/parts.json" || fail "export: graph parts not used"
"$mpi" export "$tmp/mesh" --format raw --out "$tmp/alone.mpi" >/dev/null || fail "export alone"
"$weaver" export "$tmp/mesh.serial" --format raw --out "$tmp/alone.serial" --quiet >/dev/null
diff -r "$tmp/alone.serial" "$tmp/alone.mpi" >/dev/null || fail "export on one rank differs"
# No output into a database: refused with one line and status 2 before any
# rank writes, the database unchanged.
before=$(cd "$tmp/mesh" && find . -type f ! -name LOCK -exec md5sum {} + | sort)
for out in "$tmp/mesh/MANIFEST" "$tmp/mesh/parts" "$tmp/mesh"; do
  status=0
  run 2 "$mpi" export "$tmp/mesh" --format raw --out "$out" >/dev/null 2>"$tmp/err" || status=$?
  [ "$status" = 2 ] && grep -q "weaver database" "$tmp/err" ||
    fail "export --out $out: status $status, $(cat "$tmp/err")"
done
[ "$(cd "$tmp/mesh" && find . -type f ! -name LOCK -exec md5sum {} + | sort)" = "$before" ] ||
  fail "a refused export changed the database"
set +e
run 3 "$mpi" export "$tmp/mesh" --format raw --parts 4 --out "$tmp/bad" >/dev/null 2>"$tmp/err"
code=$?
set -e
[ "$code" = 2 ] && grep -q "number of ranks" "$tmp/err" || fail "export --parts 4 on 3: exit $code"
# A rank whose write fails: one line naming it, exit 1, no output left.
set +e
mpirun -np 1 "$mpi" export "$tmp/mesh" --format raw --out "$tmp/bad" : \
       -np 1 env WEAVER_FAIL_AT=1 "$mpi" export "$tmp/mesh" --format raw --out "$tmp/bad" \
       >/dev/null 2>"$tmp/err"
code=$?
set -e
[ "$code" = 1 ] && grep -q "^weaver-mpi export: rank 1: " "$tmp/err" ||
  fail "export with rank 1 failing: exit $code: $(cat "$tmp/err")"
[ ! -e "$tmp/bad" ] && [ ! -e "$tmp/bad.tmp" ] || fail "export with rank 1 failing left files"
echo "ok  export raw and pvtu, one part a rank, as the serial export's files"
# The readers on the shards answer as on the compacted tables.
readers() {  # suffix
  "$weaver" query "$tmp/mesh" locate 50000 50000 1000 >"$tmp/q.$1"
  "$weaver" query "$tmp/mesh" node 12345 >>"$tmp/q.$1"
  "$weaver" export "$tmp/mesh" --format vtu --out "$tmp/mesh.$1.vtu" --quiet >/dev/null
  "$weaver" slice "$tmp/mesh" --axis z --at 1000 --units m --color vs --out "$tmp/mesh.$1.png" >/dev/null
  "$weaver" partition "$tmp/mesh" --parts 3 | sed -E 's/[0-9.]+s$//' >"$tmp/p.$1"  # less its time
}
readers sharded
"$weaver" compact "$tmp/mesh" >/dev/null
readers compact
for f in q p mesh; do
  for x in "" .vtu .png; do
    [ -e "$tmp/$f.sharded$x" ] || continue
    cmp -s "$tmp/$f.sharded$x" "$tmp/$f.compact$x" || fail "mesh: $f$x on the shards differs"
  done
done
for t in octants nodes; do
  [ "$(md5sum "$tmp/mesh"/$t-*.bt | cut -d' ' -f1)" = "$(md5sum "$tmp/mesh.serial"/$t-*.bt | cut -d' ' -f1)" ] ||
    fail "mesh -np 3: table $t differs from the serial mesh's"
done
echo "ok  mesh on 3 ranks: both tables as the serial mesh's"

# The exchanges cut into rounds of 256 bytes a peer (as blobs past MPI's int
# counts are): the same tables.
WEAVER_MPI_ROUND_BYTES=256 run 3 -x WEAVER_MPI_ROUND_BYTES "$mpi" mesh "$tmp/rounds" \
  --model basin --freq 0.2 --quiet >/dev/null || fail "mesh in small rounds"
"$weaver" compact "$tmp/rounds" >/dev/null
for t in octants nodes; do
  [ "$(md5sum "$tmp/rounds"/$t-*.bt | cut -d' ' -f1)" = "$(md5sum "$tmp/mesh.serial"/$t-*.bt | cut -d' ' -f1)" ] ||
    fail "mesh in small rounds: table $t differs from the serial mesh's"
done
echo "ok  exchanges in rounds of 256 bytes a peer"

# More ranks than the work: a tiny octree on 4 ranks, some left empty.
run 4 "$mpi" construct "$tmp/tiny" --model halfspace --freq 0.02 --domain 25000,25000,25000 --quiet >"$tmp/out"
"$weaver" construct "$tmp/tiny.serial" --model halfspace --freq 0.02 --domain 25000,25000,25000 --quiet >/dev/null
grep -q "(no shard)" "$tmp/out" || fail "tiny: expected an empty rank"
"$weaver" compact "$tmp/tiny" >/dev/null
[ "$(table_md5 "$tmp/tiny")" = "$(table_md5 "$tmp/tiny.serial")" ] || fail "tiny: compacted table differs"
# Balance and extract on the same 4 ranks (one family of leaves: one rank
# takes it all), to the serial tables.
run 4 "$mpi" balance "$tmp/tiny" --quiet >/dev/null || fail "tiny: balance on 4 ranks"
run 4 "$mpi" extract "$tmp/tiny" --quiet >/dev/null || fail "tiny: extract on 4 ranks"
"$weaver" balance "$tmp/tiny.serial" --quiet >/dev/null
"$weaver" extract "$tmp/tiny.serial" --quiet >/dev/null
"$weaver" compact "$tmp/tiny" >/dev/null
[ "$(md5sum "$tmp/tiny"/nodes-*.bt | cut -d' ' -f1)" = "$(md5sum "$tmp/tiny.serial"/nodes-*.bt | cut -d' ' -f1)" ] ||
  fail "tiny: the node table differs"
echo "ok  more ranks than work"

# Ranks given different arguments: one line, exit 2, nothing written.
set +e
mpirun -np 1 "$mpi" construct "$tmp/odd" --model basin --freq 0.2 : \
       -np 1 "$mpi" construct "$tmp/odd" --model basin --freq 0.3 2>"$tmp/err" >/dev/null
code=$?
set -e
[ "$code" = 2 ] || fail "different arguments: exit $code"
grep -q "different arguments" "$tmp/err" || fail "different arguments: $(cat "$tmp/err")"
[ ! -e "$tmp/odd" ] || fail "different arguments: a database was made"
echo "ok  different arguments refused"

# A database some rank cannot see (the same relative path, from another
# working directory): one line naming that rank and its file, exit 1.
mkdir -p "$tmp/seen" "$tmp/unseen"
set +e
mpirun -np 1 --wdir "$tmp/seen" "$mpi" construct db --model basin --freq 0.1 --quiet : \
       -np 1 --wdir "$tmp/unseen" "$mpi" construct db --model basin --freq 0.1 --quiet \
       >/dev/null 2>"$tmp/err"
code=$?
set -e
[ "$code" = 1 ] && grep -q "^weaver-mpi construct: rank 1: .*db/octants-" "$tmp/err" ||
  fail "a database rank 1 cannot see: exit $code: $(cat "$tmp/err")"
[ "$(grep -c '^weaver-mpi' "$tmp/err")" = 1 ] || fail "unseen database: $(cat "$tmp/err")"
echo "ok  a database some rank cannot see: one line naming the rank"

# A rank whose write fails, and a rank killed at each of its durable steps, in
# each stage, rank 1 and rank 0 (which also commits the manifest, and for
# mesh publishes the staged shards): the command fails (naming the failed
# rank), and the database is the old one, byte for byte, or, where rank 0
# died after its commit's rename, the new one, byte for byte as the run that
# was not killed left it.
faults() {  # rank, stage, the database before it (copied fresh for every try), stage options...
  local rank=$1 stage=$2 base=$3; shift 3
  local old=$tmp/old steps code new_md5 new_seen=0
  # mpirun's two groups: the rank under test gets the environment.
  run_ranks() {  # env words for the rank under test, then the database
    local envs=$1 db=$2
    if [ "$rank" = 0 ]; then
      timeout 300 mpirun -np 1 env $envs "$mpi" "$stage" "$db" "${opts[@]}" --quiet : \
                         -np 1 "$mpi" "$stage" "$db" "${opts[@]}" --quiet
    else
      timeout 300 mpirun -np 1 "$mpi" "$stage" "$db" "${opts[@]}" --quiet : \
                         -np 1 env $envs "$mpi" "$stage" "$db" "${opts[@]}" --quiet
    fi
  }
  local opts=("$@")
  rm -rf "$tmp/count" && cp -r "$base" "$tmp/count"
  # The rank's own steps, counted in the same two-rank run the kills use.
  # (Its stderr goes nowhere, so the count goes to a file.)
  rm -f "$tmp/steps"
  run_ranks "WEAVER_CRASH_AT=0 WEAVER_CRASH_STEPS_FILE=$tmp/steps" "$tmp/count" \
    >/dev/null 2>&1 || fail "$stage: counting run"
  new_md5=$(live_md5 "$tmp/count")
  steps=$(cat "$tmp/steps" 2>/dev/null || true)
  [ -n "$steps" ] && [ "$steps" -gt 0 ] || fail "$stage: no step count for rank $rank"
  local fired=0
  for step in $(seq 1 "$steps"); do
    # Killed at every step; a failed write (an error, handled as any other)
    # at the first, middle and last, to keep CI short.
    local kinds=CRASH
    if [ "$step" = 1 ] || [ "$step" = $(( (steps + 1) / 2 )) ] || [ "$step" = "$steps" ]; then
      kinds="FAIL CRASH"
    fi
    for what in $kinds; do
      rm -rf "$old" && cp -r "$base" "$old"
      local old_md5 now_md5
      old_md5=$(live_md5 "$old")
      set +e
      run_ranks "WEAVER_${what}_AT=$step" "$old" >/dev/null 2>"$tmp/err"
      code=$?
      set -e
      [ "$code" != 124 ] || fail "$stage: $what at step $step of rank $rank: the job hung"
      # Every step counted is one the rank takes: the point armed there fires,
      # a death (the simulator's exit status 137) or a one-line failure.
      [ "$code" != 0 ] || fail "$stage: $what at step $step of $steps (rank $rank) did not fire"
      if [ "$what" = CRASH ]; then
        grep -q "Exit code: *137" "$tmp/err" ||
          fail "$stage: CRASH at step $step: rank $rank did not die there: $(cat "$tmp/err")"
      fi
      fired=$((fired + 1))
      if [ "$what" = FAIL ]; then
        # mesh names the stage that failed.
        local names=$stage
        [ "$stage" = mesh ] && names="construct|balance|extract|boundary"
        grep -Eq "^weaver-mpi ($names): rank $rank: " "$tmp/err" ||
          fail "$stage FAIL at $step of rank $rank: $(cat "$tmp/err")"
        # mpirun adds its own banner about the exit status; weaver says one line.
        [ "$(grep -c '^weaver-mpi' "$tmp/err")" = 1 ] ||
          fail "$stage FAIL at $step of rank $rank: $(cat "$tmp/err")"
      fi
      now_md5=$(live_md5 "$old")
      if [ "$now_md5" != "$old_md5" ]; then
        # Only rank 0 commits, and only its last steps (the manifest's rename
        # and the directory's sync) may leave the new state.
        [ "$rank" = 0 ] && [ "$now_md5" = "$new_md5" ] ||
          fail "$stage: $what at step $step of rank $rank: neither the old database nor the new"
        [ "$step" = "$steps" ] ||
          fail "$stage: $what at step $step of $steps (rank 0) left the new database before its last step"
        new_seen=$((new_seen + 1))
      fi
      "$weaver" verify "$old" >/dev/null || fail "$stage $what at $step: the database does not verify"
    done
  done
  echo "ok  $stage: rank $rank killed at each of its $steps durable steps (failing at 3; $fired points fired) leaves the old database ($new_seen times the new one)"
}
"$weaver" construct "$tmp/f.built" --model basin --freq 0.1 --quiet >/dev/null
for rank in 1 0; do
  faults $rank construct "$tmp/f.built" --model basin --freq 0.2
  faults $rank balance "$tmp/f.built"
done
cp -r "$tmp/f.built" "$tmp/f.balanced"
"$weaver" balance "$tmp/f.balanced" --quiet >/dev/null
faults 1 extract "$tmp/f.balanced"
faults 0 extract "$tmp/f.balanced"
# mesh as a whole, over a finished mesh: construct's shards (or balance's in
# their place) and extract's are staged and go live with the boundary's, so
# a rank killed anywhere leaves the old mesh, every table, byte for byte.
"$weaver" mesh "$tmp/f.mesh" --model basin --freq 0.1 --quiet >/dev/null
for rank in 1 0; do
  faults $rank mesh "$tmp/f.mesh" --model basin --freq 0.2
  faults $rank mesh "$tmp/f.mesh" --model basin --freq 0.2 --unbalanced
done
