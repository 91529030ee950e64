#!/usr/bin/env bash
# Idempotent setup for a fresh Debian bookworm machine: system packages the
# project needs (software Vulkan driver from bookworm-backports when no GPU
# Vulkan driver is present, espeak-ng, flite for the speech benchmark's
# held-out voices, tmux), a virtual environment in .venv, and the project
# installed into it with its pinned dependencies.
set -euo pipefail
cd "$(dirname "$0")/.."

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

have_gpu_vulkan() {
    # NVIDIA's driver installs its own Vulkan ICD; Mesa's ICDs need a new enough Mesa.
    ls /usr/share/vulkan/icd.d/ /etc/vulkan/icd.d/ 2>/dev/null | grep -q nvidia
}

mesa_is_new_enough() {
    local v
    v=$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)
    [ -n "$v" ] && dpkg --compare-versions "$v" ge 24.3
}

apt_packages=(espeak-ng flite sphinxtrain sphinxbase-utils tmux libportaudio2 libgl1 libegl1 libglib2.0-0)
missing=()
for p in "${apt_packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
need_mesa=0
if ! have_gpu_vulkan && ! mesa_is_new_enough; then need_mesa=1; fi

if [ ${#missing[@]} -gt 0 ] || [ $need_mesa -eq 1 ]; then
    if [ $need_mesa -eq 1 ] && ! grep -rqs "bookworm-backports" /etc/apt/sources.list /etc/apt/sources.list.d/; then
        echo "deb http://deb.debian.org/debian bookworm-backports main" | $SUDO tee /etc/apt/sources.list.d/bookworm-backports.list >/dev/null
    fi
    $SUDO apt-get update -qq
    if [ ${#missing[@]} -gt 0 ]; then
        DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
    fi
    if [ $need_mesa -eq 1 ]; then
        DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq -t bookworm-backports mesa-vulkan-drivers libvulkan1 >/dev/null
    fi
fi

PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$PY" -m venv .venv
fi
stamp=.venv/.hfpbd-installed
if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ]; then
    .venv/bin/pip install -q --upgrade pip
    .venv/bin/pip install -q -e ".[test]"
    # sapien depends on opencv-python; keep only the headless build (same cv2 API).
    if .venv/bin/pip show -q opencv-python >/dev/null 2>&1; then
        .venv/bin/pip uninstall -q -y opencv-python
        .venv/bin/pip install -q --force-reinstall --no-deps "opencv-python-headless==4.11.0.86"
    fi
    .venv/bin/python scripts/check_render.py
    touch "$stamp"
fi
