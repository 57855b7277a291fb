"""Reads a Sponge schematic with nbtlib (PyPI), an NBT reader independent of voxbrick's, and
prints its version, size, palette and the count of each palette entry's blocks as JSON (the
block data decoded from its varints here). Usage: schem_read.py FILE.schem"""
import json
import sys

import nbtlib

root = nbtlib.load(sys.argv[1])
s = root["Schematic"] if "Schematic" in root else root
version = int(s["Version"])
blocks = s["Blocks"] if version == 3 else s
data = bytes(int(b) & 0xFF for b in (blocks["Data"] if version == 3 else blocks["BlockData"]))
palette = {str(k): int(v) for k, v in blocks["Palette"].items()}
counts = {}
i = 0
while i < len(data):
    value, shift = 0, 0
    while True:
        b = data[i]
        i += 1
        value |= (b & 0x7F) << shift
        if not b & 0x80:
            break
        shift += 7
    counts[value] = counts.get(value, 0) + 1
names = {v: k for k, v in palette.items()}
json.dump(
    {
        "version": version,
        "size": [int(s["Width"]) & 0xFFFF, int(s["Height"]) & 0xFFFF, int(s["Length"]) & 0xFFFF],
        "blocks": {names[k]: n for k, n in counts.items()},
    },
    sys.stdout,
)
