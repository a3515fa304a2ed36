#!/usr/bin/env bash
# table_hashes.sh WEAVER_BINARY WORKDIR: runs a fixed set of writers (construct,
# balance, extract sort/search/LSM with 1 and 2 threads and small budgets, import
# of shuffled octants, mesh, export) and prints one md5 per table or file written.
# Run it with the binaries of two builds and diff: a refactor that must not
# change output shows here.  About 30 s.
set -euo pipefail
B=$1; W=$2; rm -rf "$W"; mkdir -p "$W"
h() { # step db table
  local f; f=$(ls "$2"/$3-*.bt | head -1); echo "$1 $3 $(md5sum < "$f" | cut -c1-32)"; }
q() { "$@" >/dev/null 2>&1; }
q $B construct $W/c --model basin --freq 0.3; h construct $W/c octants
q $B balance $W/c; h balance $W/c octants
q $B extract $W/c; h extract-sort-t1 $W/c nodes
q $B extract $W/c --threads 2 --memory 4M; h extract-sort-t2-4M $W/c nodes
q $B extract $W/c --algorithm search; h extract-search-btree $W/c nodes
q $B extract $W/c --algorithm search --store lsm --memory 2M; h extract-search-lsm $W/c nodes
q $B construct $W/l --model loh1 --freq 0.25 --memory 1M; h construct-loh1-1M $W/l octants
q $B generate $W/r.txt --kind random --leaves 300000 --max-level 12 --shuffle --seed 7
q $B import $W/r --octants $W/r.txt --memory 2M; h import-shuffled-2M $W/r octants
q $B balance $W/r --memory 1M; h balance-1M $W/r octants
q $B extract $W/r --threads 2; h extract-t2 $W/r nodes
q $B mesh $W/m --model halfspace --freq 0.3 --threads 2; h mesh $W/m octants; h mesh $W/m nodes
$B export $W/m --nodes $W/m.nodes.csv --elements $W/m.el.csv >/dev/null 2>&1
echo "export-csv nodes $(md5sum < $W/m.nodes.csv | cut -c1-32)"
echo "export-csv elements $(md5sum < $W/m.el.csv | cut -c1-32)"
