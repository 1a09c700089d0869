#!/bin/sh
# Seeds each target's corpus from the repository's examples (and from any further files given:
# `fuzz/seed.sh path/to/more/files...` copies each into the corpus its extension names).
set -e
cd "$(dirname "$0")"
ex=../examples
mkdir -p corpus/case_json corpus/dxf corpus/svg corpus/stl corpus/tooldb corpus/shape corpus/rough_small corpus/gcode
cp "$ex"/cases/*.json "$ex"/3d/*.json corpus/case_json/
cp "$ex"/cases/*.json corpus/rough_small/
cp "$ex"/parts/*.stl corpus/stl/
cp "$ex"/tools/*.json corpus/tooldb/
cp "$ex"/shapes/*.json corpus/shape/
cp "$ex"/programs/*.ngc corpus/gcode/
for f in "$@"; do
    case "$f" in
        *.dxf | *.DXF) cp "$f" corpus/dxf/ ;;
        *.svg | *.SVG) cp "$f" corpus/svg/ ;;
        *.stl | *.STL) cp "$f" corpus/stl/ ;;
        *.json) cp "$f" corpus/case_json/ ;;
        *.ngc | *.nc | *.gcode | *.tap) cp "$f" corpus/gcode/ ;;
    esac
done
