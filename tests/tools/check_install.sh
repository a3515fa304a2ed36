#!/usr/bin/env bash
# The library API as a user meets it: `cmake --install` the build into a
# fresh prefix, build examples/ against the installed package with
# find_package(weaver), run both examples on a mesh and compare what they
# print with the command line's answers; then the Python module from the
# same prefix (tests/tools/check_python_api.py).
# usage: check_install.sh SOURCE_DIR BUILD_DIR WORK_DIR
set -euo pipefail
src=$1 build=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
prefix=$work/prefix
cmake --install "$build" --prefix "$prefix" > "$work/install.log"
cmake -S "$src/examples" -B "$work/examples" -DCMAKE_PREFIX_PATH="$prefix" > "$work/configure.log"
cmake --build "$work/examples" > "$work/build.log"
weaver=$prefix/bin/weaver
db=$work/basin.db
"$weaver" mesh "$db" --model basin --freq 0.05 --quiet > /dev/null

fail() { echo "check_install: $*" >&2; exit 1; }

# The installed library exports its API and nothing else: C functions named
# weaver_* and C++ symbols of weaver::api (and their typeinfo and vtables).
lib=$(ls "$prefix"/lib*/libweaver.so | head -1)
exports=$(nm -D --defined-only -C "$lib" | cut -d' ' -f3-)
[ -n "$(echo "$exports" | grep '^weaver_open')" ] || fail "weaver_open is not exported"
[ -n "$(echo "$exports" | grep '^weaver::api::MeshDatabase')" ] || fail "weaver::api is not exported"
strays=$(echo "$exports" | grep -v -E '^(weaver_|weaver::api::|(typeinfo|typeinfo name|vtable) for weaver::api::)' || true)
[ -z "$strays" ] || fail "exports more than its API: $(echo "$strays" | head -3 | tr '\n' ';')"
summary=$("$work/examples/mesh_summary" "$db")
stat=$("$weaver" stat "$db")
count() { echo "$stat" | awk -v t="$1" -v f="$2" '$1 == "table" && $2 == t {on = 1} on && $1 == f {print $2; exit}'; }
[ "$(echo "$summary" | awk '$1 == "elements" {print $2}')" = "$(count octants records)" ] ||
  fail "element count differs from weaver stat"
[ "$(echo "$summary" | awk '$1 == "nodes" {print $2}')" = "$(count nodes records)" ] ||
  fail "node count differs from weaver stat"
for kind in anchored edge-dangling face-dangling; do
  short=${kind%-dangling}
  [ "$(echo "$summary" | awk -v k="$short" '$1 == k {print $2}')" = "$(count nodes "$kind")" ] ||
    fail "$kind nodes differ from weaver stat"
done
levels=$(echo "$summary" | awk '$1 == "level" {print $2, $3}')
stat_levels=$(echo "$stat" | awk '$1 == "table" {t = $2} t == "octants" && $1 == "level" {print $2, $3}')
[ "$levels" = "$stat_levels" ] || fail "per-level counts differ: $levels / $stat_levels"

# The C example against 'weaver query locate --points' on the same points.
printf '1000 2000 3000\n60000 70000 8000\n900000 900000 900000\n' > "$work/points.txt"
"$work/examples/locate_points" "$db" < "$work/points.txt" > "$work/c.txt"
"$weaver" query "$db" locate --points "$work/points.txt" --format tsv |
  awk -F'\t' 'NR > 1 {if ($4 == "inside") print $1, $2, $3, $5, $6, $12; else print $1, $2, $3, "outside"}' > "$work/cli.txt"
diff "$work/c.txt" "$work/cli.txt" > /dev/null || fail "locate_points differs: $(diff "$work/c.txt" "$work/cli.txt")"

/usr/bin/python3 "$src/tests/tools/check_python_api.py" "$prefix/share/weaver/python" "$weaver" "$db" "$work"
echo "check_install: ok"
