# Shared set-up for scripts/run and scripts/test. Idempotent: each step checks before it acts.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv"

log() { printf '\033[1m[neurarm]\033[0m %s\n' "$*" >&2; }

as_root() {
  if [ "$(id -u)" = 0 ]; then "$@"; elif command -v sudo >/dev/null; then sudo "$@"; else
    log "need root to run: $*"; return 1; fi
}

# ensure_debian_packages PKG...: installs the Debian packages that are missing.
ensure_debian_packages() {
  local missing=()
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  log "installing Debian packages: ${missing[*]}"
  as_root apt-get update -qq
  DEBIAN_FRONTEND=noninteractive as_root apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

# ensure_venv REQUIREMENTS [VENV]: a Python venv (default .venv) with the pinned packages;
# reinstalls only when the requirements file changes.
ensure_venv() {
  local req="$1" venv="${2:-$VENV}"
  local stamp="$venv/.requirements"
  if [ ! -x "$venv/bin/python" ]; then
    log "creating Python venv in ${venv#$ROOT/}"
    python3 -m venv "$venv" 2>/dev/null || { ensure_debian_packages python3-venv; python3 -m venv "$venv"; }
  fi
  if ! cmp -s "$req" "$stamp"; then
    log "installing Python packages from ${req#$ROOT/}"
    "$venv/bin/python" -m pip install -q --disable-pip-version-check -r "$req"
    cp "$req" "$stamp"
  fi
}

# ensure_rust_components NAME...: adds the rustup components (rustfmt, clippy) the toolchain
# lacks; the test command needs them.
ensure_rust_components() {
  local missing=()
  for c in "$@"; do
    case "$c" in
      rustfmt) cargo fmt --version >/dev/null 2>&1 || missing+=("$c") ;;
      clippy) cargo clippy --version >/dev/null 2>&1 || missing+=("$c") ;;
    esac
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  log "adding Rust components: ${missing[*]}"
  rustup component add "${missing[@]}"
}
