#!/usr/bin/env bash
# Installs the Debian packages Ramure's GUI tests need on a headless machine:
# a virtual X server, the xcb libraries Qt 6 loads, and Debian's chromium (the
# browser the JupyterLab test drives; Ramure never downloads a browser build), and PostgreSQL's
# server for the study tests on PostgreSQL. Does nothing when they
# are present or when we cannot install (not root, no sudo).
set -u
need=()
command -v xvfb-run >/dev/null 2>&1 || need+=(xvfb xauth)
command -v chromium >/dev/null 2>&1 || need+=(chromium fonts-dejavu-core)
# PostgreSQL's server programs: the study tests run a throwaway cluster (initdb, pg_ctl) on 127.0.0.1.
ls /usr/lib/postgresql/*/bin/initdb >/dev/null 2>&1 || need+=(postgresql)
for lib in libxcb-cursor.so.0 libxkbcommon-x11.so.0 libEGL.so.1 libGL.so.1 libGLX_mesa.so.0 libxcb-icccm.so.4 libfontconfig.so.1 libdbus-1.so.3; do
  ldconfig -p 2>/dev/null | grep -q "$lib" || { need+=(libxcb-cursor0 libxkbcommon-x11-0 libegl1 libgl1 libxcb-icccm4 libxcb-image0 libxcb-keysyms1 libxcb-randr0 libxcb-render-util0 libxcb-shape0 libxcb-xinerama0 libxcb-xkb1 libfontconfig1 libdbus-1-3 libglu1-mesa libxrender1 libxi6 libgl1-mesa-dri libglx-mesa0); break; }
done
[ ${#need[@]} -eq 0 ] && exit 0
if [ "$(id -u)" = 0 ]; then SUDO=""; elif command -v sudo >/dev/null 2>&1; then SUDO="sudo -n"; else
  echo "sysdeps: missing ${need[*]} and cannot install (not root); GUI tests will be skipped" >&2; exit 0; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq >/dev/null && $SUDO apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null \
  && echo "sysdeps: installed ${need[*]}" || echo "sysdeps: apt-get failed for ${need[*]}" >&2
exit 0
