#!/usr/bin/env bash
# Installs everything fploc needs on a fresh Debian 12 machine (idempotent; quick when all is present).
set -euo pipefail
PKGS=(
  build-essential cmake ninja-build ccache pkg-config git iproute2 util-linux procps ca-certificates
  libeigen3-dev libceres-dev libpcl-dev
  liblcm-dev liblcm-bin liblcm-java default-jre-headless default-jdk-headless libjchart2d-java libglib2.0-dev
  libprotobuf-dev protobuf-compiler
  libgtest-dev libgmock-dev libbenchmark-dev
  libfreetype-dev fonts-dejavu-core   # text in PNG pictures (legends, scale bars: modules/floorplan/src/text.cpp)
  nlohmann-json3-dev libyaml-dev libpng-dev libcli11-dev libcpp-httplib-dev libssl-dev libpcap-dev libnanoflann-dev
  libbz2-dev liblz4-dev libzstd-dev zlib1g-dev libisal-dev lz4
  libsqlite3-dev   # ROS 2 rosbag2 sqlite3 bags (.db3): modules/recording/src/db3_reader.cpp
  python3
  libboost-dev openssh-client openssh-server
  python3-ezdxf   # tests: `fploc map diff` DXF read back by a CAD library (ezdxf, strict read + audit)
  python3-matplotlib   # tools/bench_real/plot_errors.py (per-scan error plots of fploc-real-track, diagnostic)
)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  echo "fploc setup: installing ${missing[*]}" >&2
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi
bash "$(dirname "${BASH_SOURCE[0]}")/setup-web.sh"
