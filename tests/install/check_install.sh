#!/usr/bin/env bash
# The installed tactforce, used from outside the tree (tests/install/CMakeLists.txt):
#   1. cmake --install BUILD --prefix PREFIX (a fresh temporary directory);
#   2. the installed files: headers (generated ones too), binaries reporting
#      VERSION, no path into the source or build tree;
#   3. examples/cpp configured with find_package(tactforce) against PREFIX
#      only, built and run; its output checked;
#   4. pkg-config: tactforce.pc found through PKG_CONFIG_PATH=PREFIX/LIBDIR/pkgconfig,
#      its --cflags --libs used to compile, link and run the same example.
# Any failure exits non-zero naming the step; the temporary directory is
# removed on success and kept (path printed) on failure.
set -euo pipefail

usage() { echo "usage: $0 --build DIR --source DIR --version X.Y.Z --libdir DIR --cmake EXE --cxx EXE --pkg-config EXE" >&2; exit 2; }
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build=$2 ;; --source) source=$2 ;; --version) version=$2 ;;
    --libdir) libdir=$2 ;; --cmake) cmake=$2 ;; --cxx) cxx=$2 ;; --pkg-config) pkgconfig=$2 ;;
    *) usage ;;
  esac
  shift 2
done
[[ -n "${build:-}" && -n "${source:-}" && -n "${version:-}" && -n "${libdir:-}" && -n "${cmake:-}" && -n "${cxx:-}" && -n "${pkgconfig:-}" ]] || usage

work=$(mktemp -d "${TMPDIR:-/tmp}/tactforce-install-test.XXXXXX")
prefix=$work/prefix
step="setup"
finish() {
  local rc=$?
  if [[ $rc -eq 0 ]]; then rm -rf "$work"; else echo "FAILED at: $step (files kept in $work)" >&2; fi
}
trap finish EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

step="cmake --install"
"$cmake" --install "$build" --prefix "$prefix" > "$work/install.log"

step="installed files"
for f in include/tactforce/planner/solver.h include/tactforce/api/services.h \
         include/tactforce/api/version.h include/tactforce/inertia/fit.h \
         include/tactforce/v1/planner.pb.h include/tactforce/v1/planner.grpc.pb.h \
         include/tactforce/v1/info.pb.h include/tactforce/v1/info.grpc.pb.h \
         include/tactforce/v1/info.proto \
         "$libdir/cmake/tactforce/tactforceConfig.cmake" \
         "$libdir/cmake/tactforce/tactforceConfigVersion.cmake" \
         "$libdir/cmake/tactforce/tactforceTargets.cmake" \
         "$libdir/pkgconfig/tactforce.pc" bin/tactforce bin/tactforce-server; do
  [[ -e "$prefix/$f" ]] || fail "not installed: $f"
done
for lib in io planner estimator inertia sim audit proto api; do
  compgen -G "$prefix/$libdir/libtactforce_$lib.*" > /dev/null || fail "not installed: libtactforce_$lib"
done
grep -q "TACTFORCE_VERSION_STRING \"$version\"" "$prefix/include/tactforce/api/version.h" ||
  fail "installed version.h does not say $version"
# The package must not point back into the trees it was built from.
if grep -rlF -e "$source" -e "$build" "$prefix/$libdir/cmake" "$prefix/$libdir/pkgconfig"; then
  fail "installed package files name the source or build tree (above)"
fi
for exe in tactforce tactforce-server; do
  out=$("$prefix/bin/$exe" --version)
  [[ "$out" == "$exe $version" ]] || fail "$exe --version printed '$out', expected '$exe $version'"
done

check_example_output() {  # $1: the example's output file
  grep -qx "tactforce $version (.* build)" "$1" || fail "example: no 'tactforce $version' line"
  grep -qx "status: OPTIMAL" "$1" || fail "example: plan not OPTIMAL"
  grep -qx "ipopt agrees: yes" "$1" || fail "example: geometric and Ipopt plans disagree"
  [[ $(grep -cE "^(thumb|index|middle) +f = \(" "$1") -eq 3 ]] || fail "example: not one force per finger"
  grep -q '^api response: .*"status": *"PLAN_STATUS_OPTIMAL"' "$1" || fail "example: api response not OPTIMAL"
}

step="find_package consumer: configure"
"$cmake" -S "$source/examples/cpp" -B "$work/example" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON \
  -DCMAKE_CXX_COMPILER="$cxx" > "$work/configure.log" 2>&1 || { cat "$work/configure.log" >&2; false; }
grep -q "tactforce $version from $prefix/" "$work/configure.log" ||
  { cat "$work/configure.log" >&2; fail "find_package did not find the package under $prefix"; }
step="find_package consumer: build"
"$cmake" --build "$work/example" -j2 > "$work/build.log" 2>&1 || { cat "$work/build.log" >&2; false; }
step="find_package consumer: run"
rc=0; "$work/example/plan_grasp" > "$work/example.out" || rc=$?
[[ $rc -eq 0 ]] || { cat "$work/example.out" >&2; fail "plan_grasp exit code $rc"; }
cat "$work/example.out"
check_example_output "$work/example.out"

step="pkg-config"
export PKG_CONFIG_PATH="$prefix/$libdir/pkgconfig"
[[ "$("$pkgconfig" --modversion tactforce)" == "$version" ]] || fail "pkg-config --modversion tactforce != $version"
flags=$("$pkgconfig" --cflags --libs tactforce)
echo "pkg-config --cflags --libs tactforce: $flags"
[[ "$flags" == *-ltactforce_planner* && "$flags" == *-ltactforce_api* ]] || fail "Libs lacks the tactforce libraries"
includedir=$("$pkgconfig" --variable=includedir tactforce)
[[ -f "$includedir/tactforce/planner/solver.h" ]] || fail "pkg-config includedir $includedir has no tactforce headers"
step="pkg-config consumer: compile, link, run"
# shellcheck disable=SC2086  # the flags are words
"$cxx" -std=c++20 -O1 "$source/examples/cpp/main.cc" -o "$work/plan_grasp_pc" $flags
rc=0; "$work/plan_grasp_pc" > "$work/example_pc.out" || rc=$?
[[ $rc -eq 0 ]] || { cat "$work/example_pc.out" >&2; fail "pkg-config build: plan_grasp exit code $rc"; }
check_example_output "$work/example_pc.out"
echo "install test: OK"
