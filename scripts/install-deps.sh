#!/usr/bin/env bash
# Installs, from Debian's packages, whatever Rubble needs that this machine lacks. Safe to run again.
set -euo pipefail
packages=(cmake ninja-build g++ ccache clang-format pkg-config
          libtbb-dev libxsimd-dev libeigen3-dev libqhull-dev nlohmann-json3-dev libgtest-dev libbenchmark-dev
          libccd-dev   # libccd: an independent collision library, used only by tests as an oracle
          gnuplot-nox  # the accuracy report's plots (rubble accuracy)
          clang libclang-rt-14-dev  # the fuzz targets: libFuzzer and the sanitizers' runtimes for clang (scripts/fuzz.sh)
          # The viewer: GLFW windows, libepoxy as the OpenGL loader, Dear ImGui (its static library carries the
          # glfw and opengl3 backends; it brings libstb, whose stb_image_write writes the screenshots), and Xvfb with
          # Mesa's software renderer (llvmpipe: OpenGL 4.5 core) for the headless screenshot tests.
          libglfw3-dev libepoxy-dev libimgui-dev libgl1-mesa-dri xvfb xauth)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}"
  sudo_cmd=(); [[ $(id -u) -ne 0 ]] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
