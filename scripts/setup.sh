# Shared by scripts/demo and scripts/test: installs missing Debian packages,
# configures and builds. Sourced, not run.
# Environment: BUILD_DIR (default build), BUILD_TYPE (default Release),
# CURVFLOW_CMAKE_ARGS (extra configure arguments).
set -euo pipefail

CURVFLOW_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${BUILD_DIR:-$CURVFLOW_ROOT/build}
BUILD_TYPE=${BUILD_TYPE:-Release}
CURVFLOW_PACKAGES="build-essential cmake ninja-build pkg-config libsuitesparse-dev libopenblas-dev libmetis-dev libstb-dev libjansson-dev"
# the Python package (python/, docs/python.md): numpy, the tests, the Dask batch
# runner, and the local install (venv + pip --no-build-isolation, no PyPI)
CURVFLOW_PACKAGES="$CURVFLOW_PACKAGES python3-numpy python3-pytest python3-distributed python3-setuptools python3-wheel python3-venv"
# the HTML report's viewer (report/, docs/report.md) is bundled at build time by
# npm + esbuild: Debian's nodejs and npm unless the machine has node and npm already
command -v node >/dev/null 2>&1 || CURVFLOW_PACKAGES="$CURVFLOW_PACKAGES nodejs"
command -v npm >/dev/null 2>&1 || CURVFLOW_PACKAGES="$CURVFLOW_PACKAGES npm"

curvflow_install_packages() {
    local missing=""
    for p in $CURVFLOW_PACKAGES; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
    done
    [ -z "$missing" ] && return 0
    echo "curvflow: installing Debian packages:$missing" >&2
    local sudo=""
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $missing >&2
}

curvflow_build() {
    local dir=$1; shift
    local generator=()
    command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
    if [ ! -f "$dir/CMakeCache.txt" ]; then
        cmake -S "$CURVFLOW_ROOT" -B "$dir" "${generator[@]}" -DCMAKE_BUILD_TYPE="$BUILD_TYPE" \
            ${CURVFLOW_CMAKE_ARGS:-} "$@" >&2
    fi
    cmake --build "$dir" --parallel "$(nproc)" >&2
}

# CHOLMOD 3.0's OpenMP loops fight OpenBLAS's threads on small machines; see
# docs/conventions.md (solver threads). The library also sets this itself.
export OMP_THREAD_LIMIT=${OMP_THREAD_LIMIT:-1}
