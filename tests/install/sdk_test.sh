#!/usr/bin/env bash
# The SDK as a user meets it. rsca is installed into a DESTDIR (as the rsca and rsca-dev packages
# would put it); the installed `rsca new component` makes a project, which is built against the
# installed tree with find_package(rsca) (and compiled once more with pkg-config) and installed
# into an SDR root of its own; the installed daemons come up, and the component runs in both of
# its forms: a process of its own (rsca::runtime) and a library a component host loads
# (rsca::component_library). The installed `rsca new device` makes a device project, built the same
# way into a library (rsca::device_library) that the installed rsca-noded loads for the generated
# DCD; its properties answer. Everything it started is stopped and checked gone.
# Usage: sdk_test.sh BUILD_DIR FLAGS SONAME   (FLAGS: the build's sanitizer flags, which a program
# linking the installed runtime needs as well; SONAME: the runtime library's)
set -euo pipefail
build="$1"
flags="$2"
soname="$3"
work="$(mktemp -d /tmp/rsca-sdk-test.XXXXXX)"
# Open to the user component processes run as (the GPP's run_as): mktemp -d makes it 0700.
chmod 755 "$work"
usr="$work/root/usr"
rsca="$usr/bin/rsca"
sdr="$work/sdr"
export RSCA_DDS_DOMAIN=$((1 + $$ % 101)) RSCA_DDS_TAG="sdk-test-$$-$RANDOM"

cleanup() {
  "$rsca" domain down --run-dir "$work/run" >/dev/null 2>&1 || true
  pkill -KILL -f "$work" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
step() { printf '== %s\n' "$*"; }
fail() { printf 'FAIL: %s\n' "$*" >&2; exit 1; }

# Waits (at most 30 s) until APP's component has ticked more than twice.
wait_ticks() {
  local app="$1" ticks=0
  for _ in $(seq 300); do
    ticks="$("$rsca" --json query "$app" 2>/dev/null |
      python3 -c 'import json,sys; print(json.load(sys.stdin)["properties"]["ticks"])' 2>/dev/null ||
      echo 0)"
    [ "$ticks" -gt 2 ] && return 0
    sleep 0.1
  done
  fail "$app did not tick (ticks = $ticks)"
}

step "install rsca into $work/root"
DESTDIR="$work/root" cmake --install "$build" --prefix /usr --strip >/dev/null

step "rsca new component Greeter"
"$rsca" new component Greeter --dir "$work/src"
if "$rsca" new component Greeter --dir "$work/src" 2>/dev/null; then
  fail "rsca new component wrote over an existing project"
fi
for bad in "no good" class Component test; do
  if "$rsca" new component "$bad" --dir "$work/src" 2>/dev/null; then
    fail "rsca new component took \"$bad\", which would not build"
  fi
done
[ -z "$(ls -A "$work/src" | grep -v '^Greeter$')" ] || fail "rsca new left something behind"

step "build it against the installed SDK (find_package) and install it into an SDR root"
cmake -S "$work/src/Greeter" -B "$work/build" -DCMAKE_PREFIX_PATH="$usr" \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="$flags" >/dev/null
cmake --build "$work/build" -j2 >/dev/null
cmake --install "$work/build" --prefix "$sdr" >/dev/null
[ -x "$sdr/dom/components/Greeter/Greeter" ] || fail "the executable was not installed"
[ -f "$sdr/dom/components/Greeter/libGreeter.so" ] || fail "the library was not installed"

step "compile it again with pkg-config"
libdir="$(dirname "$(find "$usr" -name "$soname" -print -quit)")"
pc="$(PKG_CONFIG_PATH="$libdir/pkgconfig" pkg-config --cflags --libs rsca)"
# shellcheck disable=SC2086 # pkg-config's output is a list of flags
g++ $flags "$work/src/Greeter/src/Greeter.cpp" $pc -o "$work/greeter-pkgconfig"
# grep reads all of ldd's output (not -q): ldd cut off by SIGPIPE fails the pipe (pipefail).
LD_LIBRARY_PATH="$libdir" ldd "$work/greeter-pkgconfig" | grep -F "$soname => $libdir/" >/dev/null ||
  fail "the program pkg-config built does not link the installed runtime"

# The same component as a library a host loads: its SPD naming lib<name>.so, as the generated
# SPD's description says.
spd="$sdr/dom/components/Greeter"
sed -e 's|<code type="Executable">|<code type="SharedLibrary">|' \
    -e 's|<localfile name="Greeter"/>|<localfile name="libGreeter.so"/>|' -e '/<entrypoint>/d' \
    -e 's|name="Greeter" version|name="GreeterLib" version|' "$spd/Greeter.spd.xml" >"$spd/GreeterLib.spd.xml"
mkdir -p "$sdr/dom/waveforms/GreeterLib"
sed -e 's|Greeter/Greeter.spd.xml|Greeter/GreeterLib.spd.xml|' \
    -e 's|name="Greeter" version|name="GreeterLib" version|' \
    "$sdr/dom/waveforms/Greeter/Greeter.sad.xml" >"$sdr/dom/waveforms/GreeterLib/GreeterLib.sad.xml"

step "validate the SDR root strictly"
"$rsca" validate --strict "$sdr"

step "a property the code binds and the PRF lacks is found by validate, before any launch"
[ -f "$spd/Greeter.rsca-code.json" ] || fail "the code's description is not installed beside it"
sed -i 's/property("length", length_)/property("lenght2", length_)/' "$work/src/Greeter/src/Greeter.cpp"
cmake --build "$work/build" -j2 >/dev/null
cmake --install "$work/build" --prefix "$work/sdr-misspelled" >/dev/null
if "$rsca" validate "$work/sdr-misspelled" >"$work/misspelled.txt" 2>&1; then
  fail "validate took a component whose code binds a property its PRF lacks"
fi
grep -F 'property "lenght2" is bound, but the PRF does not define it' "$work/misspelled.txt" >/dev/null ||
  { cat "$work/misspelled.txt" >&2; fail "validate did not name the misspelled property"; }

step "rsca new device Thermo: built against the installed SDK, installed into the SDR root"
"$rsca" new device Thermo --dir "$work/src"
cmake -S "$work/src/Thermo" -B "$work/build-thermo" -DCMAKE_PREFIX_PATH="$usr" \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_MODULE_LINKER_FLAGS="$flags" >/dev/null
cmake --build "$work/build-thermo" -j2 >/dev/null
cmake --install "$work/build-thermo" --prefix "$sdr" >/dev/null
thermo_dcd="$sdr/dev/nodes/Thermo_node/DeviceManager.dcd.xml"
[ -f "$sdr/dev/devices/Thermo/libThermo.so" ] || fail "the device library was not installed"
[ -f "$sdr/dev/devices/Thermo/Thermo.spd.xml" ] || fail "the device's SPD was not installed"
[ -f "$thermo_dcd" ] || fail "the device's node DCD was not installed"
if readelf -d "$sdr/dev/devices/Thermo/libThermo.so" | grep 'NEEDED.*librsca'; then
  fail "the device library links an rsca library (rsca-noded provides the code)"
fi
# The generated profiles are valid, and the DeviceManager SPD the DCD names is rsca's own
# (found in the installed profiles, so no warning says it is missing).
"$rsca" validate "$sdr"
"$rsca" validate "$thermo_dcd" >"$work/thermo-validate.txt" 2>&1 || fail "the device's DCD is invalid"
if grep -i 'missing' "$work/thermo-validate.txt" >/dev/null; then
  cat "$work/thermo-validate.txt" >&2
  fail "validating the device's DCD warns of a missing file"
fi

step "the installed daemons come up, one node with the new device"
"$rsca" domain up --nodes 1 --node "$thermo_dcd" --run-dir "$work/run" || { tail -n 20 "$work"/run/*.log >&2; fail "the daemons did not come up"; }
domaind="$(cat "$work/run/domaind.pid")"
[ "$(readlink "/proc/$domaind/exe")" = "$usr/bin/rsca-domaind" ] || fail "domaind is not the installed one"

step "launch both forms"
"$rsca" launch "$sdr/dom/waveforms/Greeter/Greeter.sad.xml"
"$rsca" launch "$sdr/dom/waveforms/GreeterLib/GreeterLib.sad.xml"
wait_ticks Greeter
wait_ticks GreeterLib
step "the data a new user looks at: rsca echo shows what Greeter_1 sends Greeter_2"
"$rsca" echo Greeter/Greeter_1.out -n 3 --wait 10s >"$work/echo.txt" 2>&1 ||
  { cat "$work/echo.txt" >&2; fail "rsca echo saw no sample of the generated connection"; }
[ "$(grep -c . "$work/echo.txt")" -ge 3 ] || { cat "$work/echo.txt" >&2; fail "rsca echo printed fewer than 3 samples"; }
"$rsca" --json show GreeterLib | grep '"state": "running"' >/dev/null || fail "GreeterLib is not running"

step "the device runs in the installed rsca-noded, and its properties answer"
noded="$(cat "$work/run/Thermo_node.pid")"
[ "$(readlink "/proc/$noded/exe")" = "$usr/bin/rsca-noded" ] || fail "the node is not the installed one"
readings=0
for _ in $(seq 300); do
  readings="$("$rsca" --json query Thermo_node:Thermo_1 2>/dev/null |
    python3 -c 'import json,sys; print(json.load(sys.stdin)["properties"]["readings"])' 2>/dev/null ||
    echo 0)"
  [ "$readings" -gt 2 ] && break
  sleep 0.1
done
[ "$readings" -gt 2 ] || { cat "$work/run/Thermo_node.log" >&2; fail "Thermo took no readings"; }
"$rsca" query Thermo_node:Thermo_1 | grep -q temperature_c || fail "Thermo has no temperature_c"

step "release, domain down, nothing left"
"$rsca" release Greeter
"$rsca" release GreeterLib
"$rsca" domain down --run-dir "$work/run"
for _ in $(seq 100); do
  pgrep -f "$work" >/dev/null || break
  sleep 0.1
done
if pgrep -af "$work"; then fail "processes left behind"; fi
echo "ok"
