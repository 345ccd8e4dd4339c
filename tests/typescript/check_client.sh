#!/usr/bin/env bash
# The contract as a generated client: openapi-typescript writes a TypeScript
# client from api/openapi.json, and client.ts, which reads every answer type
# with the type each field must have, compiles against it under tsc --strict
# (both pinned in package-lock.json beside this file).  Exit 77 (skipped)
# when node or the test's node_modules are missing (scripts/setup.sh --test
# installs them).
# Usage: check_client.sh SOURCE_DIR OUT_DIR (SPEC=FILE: another copy of the
# contract, to see the test fail on it)
set -euo pipefail
src=$1 out=$2
here=$src/tests/typescript
bin=$here/node_modules/.bin
if ! command -v node >/dev/null || [ ! -x "$bin/openapi-typescript" ] ||
  [ ! -x "$bin/tsc" ]; then
  echo "contract_typescript: node or tests/typescript/node_modules missing (scripts/setup.sh --test)"
  exit 77
fi
mkdir -p "$out"
"$bin/openapi-typescript" "${SPEC:-$src/api/openapi.json}" -o "$out/openapi.d.ts"
cp "$here/client.ts" "$out/client.ts"
"$bin/tsc" --strict --noEmit --target es2020 --module es2020 \
  --moduleResolution bundler "$out/client.ts"
echo "contract_typescript: the client of api/openapi.json compiles under tsc --strict"
