"""What a mesh library finds in a mesh voxbrick wrote: loads it with trimesh (the file's own
materials, texture or vertex colours) and prints, as JSON, its total area, its bounds and its
area per face colour (sRGB). Used by app/tests/formats/mesh.rs."""
import json
import sys

import numpy as np
import trimesh

path = sys.argv[1]
mesh = trimesh.load(path, force="mesh", process=False)
visual = mesh.visual
colours = visual.to_color().vertex_colors if visual.kind == "texture" else visual.vertex_colors
face_colours = np.asarray(colours)[mesh.faces[:, 0], :3]
areas = mesh.area_faces
by_colour = {}
for c, a in zip(map(tuple, face_colours.tolist()), areas.tolist()):
    by_colour[c] = by_colour.get(c, 0.0) + a
print(json.dumps({
    "faces": int(len(mesh.faces)),
    "area": float(mesh.area),
    "bounds": mesh.bounds.tolist(),
    "colours": [[int(r), int(g), int(b), a] for (r, g, b), a in sorted(by_colour.items())],
}))
