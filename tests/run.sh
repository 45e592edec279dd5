#!/usr/bin/env bash
# The README's test command: install what the tests need and is missing, then `cargo test`.
#
#   bash tests/run.sh [cargo test arguments...]
#
# Besides Rust, the tests drive Debian's Chromium from Node (tests/browser.rs), start a
# single-node Slurm cluster (tests/slurm.rs), run the store on a throwaway PostgreSQL cluster
# (tests/store.rs; initdb from Debian's postgresql) and read recordings back with Python's
# rerun-sdk in a venv they create (tests/recording.rs). This installs only what is missing: Node.js may come
# from another source than Debian (its own `nodejs` package ships npm, and Debian's `npm`
# conflicts with it), so Node and npm are installed only when Node is absent. Python packages go
# into venvs, never into the system.
set -euo pipefail
cd "$(dirname "$0")/.."

have() { command -v "$1" >/dev/null || [ -x "/usr/sbin/$1" ]; }

missing=()
have chromium || missing+=(chromium)
if ! have node; then
  missing+=(nodejs)
  # Debian's nodejs has no npm of its own; one from elsewhere does.
  have npm || missing+=(npm)
fi
have slurmctld || missing+=(slurmctld)
have slurmd || missing+=(slurmd)
have sbatch || missing+=(slurm-client)
# Debian keeps initdb and postgres off PATH, under /usr/lib/postgresql/<version>/bin.
compgen -G '/usr/lib/postgresql/*/bin/initdb' >/dev/null || missing+=(postgresql)
# The proxy in front of several servers (tests/serving_proxy.rs); Debian keeps it in /usr/sbin.
[ -x /usr/sbin/nginx ] || have nginx || missing+=(nginx)
# `python3 -m venv` needs ensurepip, which Debian ships apart in python3-venv.
python3 -c 'import ensurepip, venv' 2>/dev/null || missing+=(python3-venv)

if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" = 0 ]; then
    SUDO=""
  elif command -v sudo >/dev/null; then
    SUDO="sudo"
  else
    echo "tests/run.sh: the tests need these Debian packages: ${missing[*]}" >&2
    echo "install them as root (apt-get install ${missing[*]}) and run this again" >&2
    exit 1
  fi
  echo "== installing ${missing[*]} (Debian)"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi
if ! have npm; then
  echo "tests/run.sh: node is installed but npm is not: install npm for $(command -v node)" >&2
  exit 1
fi
if [ ! -d tests/browser/node_modules/playwright-core ]; then
  echo "== npm ci (tests/browser: playwright-core)"
  (cd tests/browser && npm ci --no-audit --no-fund)
fi

echo "== cargo test $*"
exec cargo test "$@"
