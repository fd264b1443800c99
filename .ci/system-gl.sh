#!/usr/bin/env bash
# Offscreen MuJoCo rendering uses EGL (MUJOCO_GL=egl). Install the system EGL/Mesa libraries
# when they are missing and we are allowed to (root on Debian/Ubuntu); otherwise say what to install.
set -u
if ldconfig -p 2>/dev/null | grep -q 'libEGL.so.1'; then
  exit 0
fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
  apt-get update -qq && apt-get install -y -qq libegl1 libegl-mesa0 libgl1-mesa-dri libgbm1 >/dev/null
else
  echo "rdmp-gym: libEGL not found; install libegl1 libegl-mesa0 libgl1-mesa-dri libgbm1 for offscreen rendering" >&2
fi
exit 0
