#!/usr/bin/env bash
# Installs every Debian package scandiff needs to build, test and run, skipping
# those already installed. Runs as root (CI) or through sudo.
set -euo pipefail

packages=(
  build-essential cmake ninja-build ccache pkg-config
  libeigen3-dev libtbb-dev libmuparser-dev
  qtbase5-dev libqt5opengl5-dev
  libvtk9-dev libvtk9-qt-dev libopenmpi-dev openmpi-bin
  libpcl-dev libflann-dev libcgal-dev liblzf-dev libgdal-dev libexpat1-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev
  python3 python3-ezdxf
  xvfb xauth imagemagick xdotool
)

# Optional groups: "fuzz" adds clang and its libFuzzer runtime (scripts/fuzz.sh).
for group in "$@"; do
  case "$group" in
    fuzz) packages+=(clang-14 libclang-rt-14-dev) ;;
    *) echo "install-deps: unknown group '$group' (known: fuzz)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages are installed"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  sudo="sudo"
fi
echo "install-deps: installing ${missing[*]}"
$sudo apt-get update -q
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
