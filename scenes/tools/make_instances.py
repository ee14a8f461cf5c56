#!/usr/bin/env python3
"""Writes scenes/instances.json: a field of 100 x 100 Stanford bunnies (bun_zipper.ply,
69,451 triangles each, about 694 million in all), each an "instance" of one hidden bunny
object with its own turn, size and place, on a ground of two triangles. The demo picture
of instancing (docs/instances.png) and volley_vs_embree's instanced scene.

    python3 scenes/tools/make_instances.py > scenes/instances.json

The same seed gives the same file."""
import json
import random

SIDE = 100        # bunnies per row and per column
SPACING = 0.3     # metres between neighbours (a bunny is about 0.15 m wide)
random.seed(7)

objects = [
    # The prototype: hidden itself (mask 0), seen only through its instances.
    {"type": "mesh", "name": "bunny", "file": "${scenes}/bun_zipper.ply", "material": "fur", "mask": 0},
    # Two triangles rather than a polygon, so that volley_vs_embree (triangles only) takes
    # the scene as it is.
    {"type": "triangles", "name": "ground", "material": "grass",
     "vertices": [[-1, 0, -1], [-1, 0, SIDE * SPACING + 1], [SIDE * SPACING + 1, 0, SIDE * SPACING + 1],
                  [SIDE * SPACING + 1, 0, -1]], "indices": [[0, 1, 2], [0, 2, 3]]},
]
for i in range(SIDE):
    for j in range(SIDE):
        scale = round(random.uniform(0.7, 1.5), 3)
        x = round(i * SPACING + random.uniform(-0.05, 0.05), 3)
        z = round(j * SPACING + random.uniform(-0.05, 0.05), 3)
        objects.append({"type": "instance", "of": "bunny", "transform": {
            "scale": scale,
            "rotate": {"axis": [0, 1, 0], "degrees": round(random.uniform(0, 360), 1)},
            # bun_zipper's feet are at y = 0.0334: set them on the ground.
            "translate": [x, round(-0.0334 * scale, 4), z]}})

scene = {
    "camera": {"eye": [13.2, 0.75, -0.9], "look_at": [15.5, 0.0, 6.0], "up": [0, 1, 0], "fov": 55},
    "render": {"width": 960, "height": 540, "spp": 4, "max_depth": 2, "integrator": "whitted",
               "background": [0.55, 0.7, 0.9]},
    "materials": {
        "fur": {"ambient": 0.1, "diffuse": [0.75, 0.68, 0.58], "specular": 0.1, "shininess": 20},
        "grass": {"ambient": 0.1, "diffuse": [0.30, 0.45, 0.25]},
    },
    "lights": [{"position": [5.0, 30.0, -20.0], "intensity": 1400}],
    "objects": objects,
}
print(json.dumps(scene, separators=(",", ":")))
