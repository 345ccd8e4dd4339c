#!/usr/bin/env bash
# Install what stickslip needs to build, from Debian's packages (Debian 12).
# As root it installs what is missing; otherwise it says what to install.
#   setup.sh          what building and running need
#   setup.sh --test   also the tools some tests use: promtool (prometheus)
#                     to check /metrics, systemd-analyze (systemd) to verify
#                     the unit, nginx in front of replicas (openssl for its
#                     throwaway certificate), python3 and its
#                     jsonschema for the examples' and the contract's checks,
#                     node and npm for the contract's linter (the pinned
#                     @redocly/cli of api/lint) and the explorer's browser
#                     test (chromium, driven by the pinned puppeteer-core of
#                     tests/browser), and the generated client's test (the
#                     pinned openapi-typescript and typescript of
#                     tests/typescript), those from the npm registry;
#                     and PostgreSQL's server, for a throwaway cluster
#                     the job store's tests run on (pg-throwaway.sh);
#                     python3-matplotlib for the README's figures
#                     (scripts/figures.py);
#                     without them those tests are skipped, so as another
#                     user their absence is only said
set -euo pipefail
pkgs=(build-essential cmake pkg-config libmicrohttpd-dev libjansson-dev libgsl-dev
  zlib1g-dev libsqlite3-dev libpq-dev)
# mkdocs builds the user's guide that the daemon serves at /docs/; the build
# goes on without it (and serves none), so as another user it is only
# said.  Pinned by the release: Debian 12 ships mkdocs 1.4.2, which
# mkdocs.yml and its built-in theme are written for.  python3-venv: the
# README installs the Python client in a venv (Debian's pip refuses to
# install into the system's Python).
extras=(mkdocs python3-venv)
if [ "${1:-}" = --test ]; then
  extras+=(prometheus nginx openssl python3 python3-jsonschema systemd chromium postgresql)
  extras+=(python3-matplotlib)
  # CITATION.cff against its schema (tests/release)
  extras+=(python3-yaml)
  command -v npm >/dev/null || extras+=(nodejs npm)
  # the Python client's tests and notebooks (python/, notebooks/)
  extras+=(python3-pytest python3-tqdm mypy python3-numpy python3-pandas python3-matplotlib
    python3-ipykernel jupyter-nbconvert python3-venv python3-setuptools python3-pip)
fi
cd "$(dirname "$0")/.."
missing=()
for p in "${pkgs[@]}" "${extras[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# the contract's linter, the browser test's driver and the generated
# client's tools, at the versions their package-lock.json pin
lint_tools() {
  if [ "${1:-}" = --test ] && command -v npm >/dev/null &&
    [ ! -x api/lint/node_modules/.bin/redocly ]; then
    (cd api/lint && npm ci --no-audit --no-fund --ignore-scripts --loglevel=error)
  fi
  if [ "${1:-}" = --test ] && command -v npm >/dev/null &&
    { [ ! -d tests/browser/node_modules/puppeteer-core ] ||
      [ ! -d tests/browser/node_modules/axe-core ]; }; then
    (cd tests/browser && PUPPETEER_SKIP_DOWNLOAD=1 npm ci --no-audit --no-fund \
      --ignore-scripts --loglevel=error)
  fi
  if [ "${1:-}" = --test ] && command -v npm >/dev/null &&
    [ ! -x tests/typescript/node_modules/.bin/tsc ]; then
    (cd tests/typescript && npm ci --no-audit --no-fund --ignore-scripts \
      --loglevel=error)
  fi
}
if [ ${#missing[@]} -eq 0 ]; then
  lint_tools "$@"
  exit 0
fi
if [ "$(id -u)" -ne 0 ]; then
  needed=()
  for p in "${missing[@]}"; do
    case " ${extras[*]} " in *" $p "*) ;; *) needed+=("$p") ;; esac
  done
  if [ ${#needed[@]} -eq 0 ]; then
    echo "the tests that use ${missing[*]} will be skipped" >&2
    exit 0
  fi
  echo "stickslip needs: ${needed[*]}" >&2
  echo "run this script as root (or: sudo apt-get install -y ${missing[*]})" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -q
apt-get install -y -q --no-install-recommends "${missing[@]}"
lint_tools "$@"
