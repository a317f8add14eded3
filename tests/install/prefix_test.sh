#!/usr/bin/env bash
# `cmake --install BUILD --prefix P` stays inside P, whatever prefix the build was configured with
# (/usr by default): nothing is written outside it (the systemd units and the nodes' DCD folder
# were written to systemd's and the system's folders), and the units start P's programs with P's
# profiles and read P's configuration. Installed through DESTDIR, so that a file outside P shows
# as one outside DESTDIR/P.
# Usage: prefix_test.sh BUILD_DIR
set -euo pipefail
build="$1"
work="$(mktemp -d /tmp/rsca-prefix-test.XXXXXX)"
trap 'rm -rf "$work"' EXIT
fail() { printf 'FAIL: %s\n' "$*" >&2; exit 1; }

prefix=/opt/rsca-prefix-test
DESTDIR="$work/root" cmake --install "$build" --prefix "$prefix" --component runtime \
  >"$work/install.log" 2>&1 || { cat "$work/install.log"; fail "cmake --install"; }

outside="$(cd "$work/root" && find . -mindepth 1 \( -type f -o -type l -o -type d -empty \) \
             | grep -v "^\.$prefix/" || true)"
[ -z "$outside" ] || fail "installed outside the prefix $prefix: $outside"

units="$work/root$prefix/lib/systemd/system"
for unit in rsca-domaind.service rsca-noded@.service; do
  [ -f "$units/$unit" ] || fail "no $unit in $prefix/lib/systemd/system"
  exec_start="$(sed -n 's/^ExecStart=\([^ ]*\).*/\1/p' "$units/$unit")"
  [ "$exec_start" = "$prefix/bin/${unit%%[@.]*}" ] ||
    fail "$unit starts \"$exec_start\", not $prefix/bin/${unit%%[@.]*}"
  [ -x "$work/root$exec_start" ] || fail "$unit starts $exec_start, which the install lacks"
  ! grep -E '(^| |-)/etc/' "$units/$unit" | grep -v '^#' ||
    fail "$unit reads the system's /etc, not $prefix/etc"
done
grep -q -- "--sdrroot $prefix/share/rsca/profiles " "$units/rsca-noded@.service" ||
  fail "rsca-noded@.service does not read $prefix's profiles"
grep -q -- "--dcd $prefix/etc/rsca/nodes/%i.dcd.xml " "$units/rsca-noded@.service" ||
  fail "rsca-noded@.service does not read its DCD from $prefix/etc/rsca/nodes"
[ -d "$work/root$prefix/etc/rsca/nodes" ] || fail "no $prefix/etc/rsca/nodes"
echo "prefix_test: everything under $prefix, units start $prefix/bin"
