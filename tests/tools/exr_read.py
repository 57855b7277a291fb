"""Reads an OpenEXR file with the Academy Software Foundation's bindings (PyPI OpenEXR) and
prints its size, pixel type and channels as JSON: the independent reader the picture tests
check voxbrick's EXR files with. Usage: exr_read.py FILE.exr"""
import json
import sys

import OpenEXR
import numpy as np

part = OpenEXR.File(sys.argv[1]).parts[0]
(x0, y0), (x1, y1) = part.header["dataWindow"]
out = {"width": int(x1 - x0 + 1), "height": int(y1 - y0 + 1), "channels": {}}
for name, channel in part.channels.items():
    pixels = np.asarray(channel.pixels)
    out["type"] = str(pixels.dtype)
    if pixels.ndim == 3:
        # Grouped RGB / RGBA: one array per letter.
        for k, letter in enumerate(name):
            out["channels"][letter] = pixels[:, :, k].astype(np.float64).ravel().tolist()
    else:
        out["channels"][name] = pixels.astype(np.float64).ravel().tolist()
json.dump(out, sys.stdout)
