#!/usr/bin/env bash
# Installs the real consumers the mesh tests check voxbrick's meshes with, into
# tests/tools/.mesh-tools (ignored by git): the Khronos glTF-Validator (npm package
# gltf-validator, run by gltf_validate.js), trimesh with numpy and Pillow (PyPI, in a venv,
# run by mesh_check.py) and the Academy Software Foundation's OpenEXR bindings (PyPI
# OpenEXR, run by exr_read.py: the picture tests read voxbrick's EXR files back with them)
# and nbtlib (PyPI, run by schem_read.py: the schematic tests read exported .schem with it).
# Needs node, npm and python3 with venv (Debian: nodejs npm
# python3-venv). Run once; the tests find the tools there (or in $VOXBRICK_MESH_TOOLS).
set -euo pipefail
dir="${VOXBRICK_MESH_TOOLS:-$(cd "$(dirname "$0")" && pwd)/.mesh-tools}"
mkdir -p "$dir"
if [ ! -d "$dir/node_modules/gltf-validator" ]; then
    npm install --silent --no-audit --no-fund --prefix "$dir" gltf-validator@2.0.0-dev.3.10 >/dev/null
fi
if [ ! -x "$dir/venv/bin/python" ] || ! "$dir/venv/bin/python" -c "import trimesh, numpy, PIL, OpenEXR, nbtlib" 2>/dev/null; then
    python3 -m venv "$dir/venv"
    "$dir/venv/bin/pip" install --quiet --disable-pip-version-check trimesh numpy pillow OpenEXR nbtlib
fi
echo "mesh tools in $dir"
