#!/usr/bin/env bash
# Rebuilds the vendored three.js bundle that swarf inlines into its HTML viewer:
#
#   viewer/build.sh
#
# - `npm ci` installs the exact versions pinned in package-lock.json (three, esbuild);
# - esbuild bundles entry.js (all of three's core API plus OrbitControls) into ONE minified
#   IIFE classic script that defines the global `THREE`;
# - a header line naming the three.js release is prepended, three's LICENSE is copied next to it;
# - the build fails if the bundle contains `</script` (any case), which would end the inline
#   <script> element the viewer puts it in, or `<!--`.
#
# Outputs: crates/swarf/src/view/three.bundle.js and crates/swarf/src/view/THREE_LICENSE.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
out_dir="$(cd "$here/.." && pwd)/crates/swarf/src/view"
cd "$here"

npm ci --no-audit --no-fund --loglevel=error

version="$(node -p 'require("./node_modules/three/package.json").version')"   # e.g. 0.187.0
revision="r${version#0.}"; revision="${revision%%.*}"            # e.g. r187

mkdir -p "$out_dir"
tmp="$(mktemp)"
trap 'rm -f "$tmp"' EXIT

node_modules/.bin/esbuild entry.js \
  --bundle --minify --format=iife --global-name=THREE \
  --legal-comments=none --target=es2020 --charset=ascii --log-level=warning \
  --outfile="$tmp" --allow-overwrite

# `</script` would close the inline element; `<!--` would switch the HTML parser into the
# script-data-escaped state, where a later `<script` changes how `</script>` is matched.
for needle in '</script' '<!--'; do
  if grep -qiF -- "$needle" "$tmp"; then
    echo "viewer/build.sh: the bundle contains '$needle', which cannot be inlined in <script>" >&2
    grep -oiF -- "$needle" "$tmp" | head -5 >&2
    exit 1
  fi
done

{
  printf '/* three.js %s (MIT, https://threejs.org), bundled by viewer/build.sh with OrbitControls; see THREE_LICENSE */\n' "$revision"
  cat "$tmp"
} > "$out_dir/three.bundle.js"
cp node_modules/three/LICENSE "$out_dir/THREE_LICENSE"

echo "viewer/build.sh: wrote $out_dir/three.bundle.js ($(wc -c < "$out_dir/three.bundle.js") bytes, three.js $revision)" >&2
