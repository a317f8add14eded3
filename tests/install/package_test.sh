#!/usr/bin/env bash
# The Debian packages (cmake/RscaPackage.cmake) as a robot's computer gets them: cpack makes rsca
# and rsca-dev from this build; each holds its files and not the other's; every library a program
# of rsca's links, outside the package, belongs to a package that rsca's Depends names; and the
# package's programs, unpacked into an empty root, find the rest of rsca from there (the CLI
# validates the installed profiles with the installed XML reader).
# Usage: package_test.sh BUILD_DIR FLAGS SONAME   (FLAGS: the build's sanitizer flags, if any;
# SONAME: the runtime library's, e.g. librsca_runtime.so.0.1)
set -euo pipefail
build="$1"
flags="$2"
runtime_soname="$3"
work="$(mktemp -d /tmp/rsca-package-test.XXXXXX)"
trap 'rm -rf "$work"' EXIT
fail() { printf 'FAIL: %s\n' "$*" >&2; exit 1; }

(cd "$build" && cpack -G DEB -B "$work" >"$work/cpack.log" 2>&1) || { cat "$work/cpack.log"; fail "cpack"; }
runtime="$(ls "$work"/rsca_*.deb)"
dev="$(ls "$work"/rsca-dev_*.deb)"

# A package's file list, listed once into a file: grep -q on a pipe ends it early, and pipefail
# then takes the writer's SIGPIPE for a failure.
listing() {
  local list="$work/$(basename "$1").list"
  [ -f "$list" ] || dpkg-deb -c "$1" | awk '{print $6}' >"$list"
  echo "$list"
}
# A file by its path in the package; `L` stands for the library folder (lib/<arch> on Debian).
has() {
  grep -Eqx "${2//L/lib(/[a-z0-9_-]+)?}" "$(listing "$1")" || fail "$(basename "$1") lacks $2"
}
lacks() { ! grep -q "$2" "$(listing "$1")" || fail "$(basename "$1") holds $2"; }
for f in ./usr/bin/rsca ./usr/bin/rsca-domaind ./usr/bin/rsca-noded ./usr/bin/rsca-component-host \
         ./usr/L/rsca/librsca_xml_reader.so ./usr/L/$runtime_soname \
         ./usr/L/rsca/librsca-gpp.so ./usr/L/rsca/librsca-host-monitor.so \
         ./usr/L/rsca/librsca-robot-devices.so \
         ./usr/libexec/rsca/rsca-producer ./usr/share/rsca/profiles/dom/domain/DomainManager.dmd.xml \
         ./usr/share/rsca/schemas/sad.xsd ./L/systemd/system/rsca-domaind.service \
         ./L/systemd/system/rsca-noded@.service ./etc/rsca/nodes/; do
  has "$runtime" "$f"
done
lacks "$runtime" "^./usr/include/"
for f in ./usr/include/rsca/component/export.hpp ./usr/include/rsca/node/device_export.hpp \
         ./usr/include/rsca/node/hosted_device.hpp ./usr/L/cmake/rsca/rscaConfig.cmake \
         ./usr/L/cmake/rsca/RscaAddComponent.cmake ./usr/L/cmake/rsca/RscaAddDevice.cmake \
         ./usr/L/pkgconfig/rsca.pc ./usr/L/librsca_runtime.so; do
  has "$dev" "$f"
done
lacks "$dev" "^./usr/bin/"
dpkg-deb -f "$dev" Depends | grep "^rsca (= " >/dev/null || fail "rsca-dev does not depend on rsca"

has "$runtime" ./usr/share/doc/rsca/copyright
has "$dev" ./usr/share/doc/rsca-dev/copyright

# The maintainer scripts (cmake/debian/): in rsca's control area, executable, POSIX sh that
# parses, `set -e`, and none enables a unit (the operator chooses which node runs; README).
control="$work/control"
dpkg-deb -e "$runtime" "$control"
for script in postinst prerm postrm; do
  f="$control/$script"
  [ -x "$f" ] || fail "rsca's control area lacks an executable $script"
  [ "$(head -n 1 "$f")" = "#!/bin/sh" ] || fail "$script is not a #!/bin/sh script"
  sh -n "$f" || fail "$script does not parse as sh"
  grep -qx 'set -e' "$f" || fail "$script does not set -e"
  sed '/^[[:space:]]*#/d' "$f" >"$work/$script.code" # its comments may name what it does not do
  ! grep -Eq '(systemctl|deb-systemd-helper|deb-systemd-invoke)[^#]* (enable|start|restart)( |$)' \
    "$work/$script.code" || fail "$script enables, starts or restarts a unit"
done
# Run as dpkg runs them, with systemd's tools stubbed (they record their calls): where systemd
# does not run (a chroot, this container) they succeed and call nothing; where it runs they
# reload it and stop the daemons on removal. postrm purge is not run: it removes the host's
# links to rsca's units.
stubs="$work/stubs"
calls="$work/systemd.calls"
mkdir -p "$stubs"
for tool in systemctl deb-systemd-invoke deb-systemd-helper; do
  printf '#!/bin/sh\necho "%s $*" >>"%s"\n' "$tool" "$calls" >"$stubs/$tool"
  chmod +x "$stubs/$tool"
done
# adduser too, in a record of its own: the test makes no user on its host.
users="$work/adduser.calls"
printf '#!/bin/sh\necho "adduser $*" >>"%s"\n' "$users" >"$stubs/adduser"
chmod +x "$stubs/adduser"
for run in "postinst configure" "prerm upgrade 0.1.0" "postinst configure 0.1.0" \
           "prerm remove" "postrm remove"; do
  # shellcheck disable=SC2086 # a script's name, then its arguments
  set -- $run
  PATH="$stubs:$PATH" sh "$control/$1" "${@:2}" >"$work/script.log" 2>&1 ||
    { cat "$work/script.log"; fail "$run exits with $?"; }
done
# The system user the nodes run components as (the GPP's run_as), made where it is missing.
getent passwd rsca >/dev/null || grep -q 'adduser --system --group .* rsca$' "$users" ||
  fail "postinst configure does not make the system user rsca"
if [ -d /run/systemd/system ]; then
  grep -q 'systemctl --system daemon-reload' "$calls" || fail "no daemon-reload under systemd"
  grep -q 'stop rsca-domaind.service' "$calls" || fail "prerm remove does not stop rsca-domaind"
elif [ -s "$calls" ]; then
  cat "$calls"
  fail "the maintainer scripts call systemd's tools where systemd does not run"
fi

# Depends: every library outside the package that an ELF file of it links directly.
root="$work/root"
dpkg-deb -x "$runtime" "$root"
libdir="$(dirname "$(find "$root" -name "$runtime_soname" -print -quit)")"
depends="$(dpkg-deb -f "$runtime" Depends | tr ',' '\n' | sed 's/(.*//; s/ //g')"
owner() { # the package that holds a library file, under either of usrmerge's paths
  local path="$1" p
  for p in "$path" "$(realpath "$path")" "${path/#\/usr\/lib/\/lib}" "${path/#\/lib/\/usr\/lib}"; do
    dpkg -S "$p" 2>/dev/null | head -1 | cut -d: -f1 && return 0
  done
  return 1
}
# The files of the libraries an ELF file names itself (NEEDED); those libraries' own needs are
# their packages' to depend on.
needed_paths() {
  local needed
  needed="$(readelf -d "$1" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')"
  LD_LIBRARY_PATH="$libdir" ldd "$1" | awk '$2 == "=>" && $3 ~ /^\// {print $1, $3}' |
    while read -r soname path; do
      grep -qx "$soname" <<<"$needed" && echo "$path"
    done
  return 0
}
checked=0
while IFS= read -r -d '' elf; do
  readelf -h "$elf" >/dev/null 2>&1 || continue
  checked=$((checked + 1))
  while read -r lib; do
    case "$lib" in "$root"/*) continue ;; esac
    pkg="$(owner "$lib")" || fail "$elf links $lib, which no package holds"
    names="$pkg $(dpkg -s "$pkg" | sed -n 's/^Provides: //p' | tr ',' ' ' | sed 's/([^)]*)//g')"
    named=0
    for n in $names; do grep -qx "$n" <<<"$depends" && named=1; done
    [ "$named" = 1 ] || fail "$elf links $lib of $pkg, which Depends lacks"
  done < <(needed_paths "$elf")
done < <(find "$root" -type f -print0)
[ "$checked" -ge 10 ] || fail "only $checked ELF files checked"

# Nothing of it names the build: a path compiled in would be a place the installed daemons load
# code from on the robot. Not under a sanitizer, whose diagnostics name the source files they
# check, the build's generated ones (unity batches, IDL code) among them.
build_real="$(realpath "$build")"
if [ -z "$flags" ] && grep -rlF -- "$build_real" "$root"; then
  fail "files of the package name the build folder $build_real"
fi

# The units start the package's own programs.
for unit in "$root"/lib/systemd/system/rsca-*.service; do
  exec_start="$(sed -n 's/^ExecStart=\([^ ]*\).*/\1/p' "$unit")"
  [ -n "$exec_start" ] && [ -x "$root$exec_start" ] ||
    fail "$(basename "$unit") starts \"$exec_start\", which the package does not hold"
done

# Each package's copyright file is in Debian's machine-readable format.
dpkg-deb -x "$dev" "$work/dev-root"
for doc in "$root/usr/share/doc/rsca/copyright" "$work/dev-root/usr/share/doc/rsca-dev/copyright"; do
  [ "$(head -n 1 "$doc")" = \
    "Format: https://www.debian.org/doc/packaging-manuals/copyright-format/1.0/" ] ||
    fail "$doc is not in the machine-readable copyright format"
  for field in '^Files: \*$' '^Copyright: ' '^License: '; do
    grep -q "$field" "$doc" || fail "$doc lacks a line $field"
  done
done

# Unpacked anywhere, the CLI finds its schemas' reader and its profiles.
"$root/usr/bin/rsca" validate --strict "$root/usr/share/rsca/profiles" >"$work/validate.log" ||
  { cat "$work/validate.log"; fail "the packaged CLI does not validate the packaged profiles"; }
echo "ok: $checked ELF files, Depends: $(echo $depends)"
