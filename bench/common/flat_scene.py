"""The flat-coloured terrain scene of the coherent-ray benchmarks: an
rt-view scene file of one `rt-view bench` terrain, seen from that mesh's
bench camera, without lights (a hit shows its material's colour), at
WIDTH × HEIGHT. Standard library only, so shell scripts can run it:

    python3 bench/common/flat_scene.py BENCH_OUT [MESH]    # MESH: 10k, 100k, 1m (default)

writes BENCH_OUT/flat_terrain_MESH.ron and prints its path.
"""

import json
import os
import sys

COLOR = (0.4, 0.6, 0.3)
WIDTH, HEIGHT = 640, 480


def rt_scene(folder, mesh, cam):
    """A scene file for rt-view next to the mesh `mesh` (its path), seen
    from the camera `cam` (the bench's JSON); returns the file's path."""
    v = lambda p: "(" + ", ".join(str(x) for x in p) + ")"  # noqa: E731
    text = f"""Scene(
    camera: (position: {v(cam['position'])}, center_of_interest: {v(cam['center_of_interest'])}, up: {v(cam['up'])}, fov_y: {cam['fov_y']}, near: {cam['near']}),
    image: (width: {WIDTH}, height: {HEIGHT}),
    background: (0, 0, 0),
    materials: {{ "ground": (color: {v(COLOR)}) }},
    objects: [ Mesh(file: "{os.path.basename(mesh)}", material: "ground") ],
)
"""
    path = os.path.join(folder, "flat_" + os.path.basename(mesh)[:-4] + ".ron")
    with open(path, "w") as f:
        f.write(text)
    return path


def terrain_scene(bench_out, mesh="1m"):
    """The flat scene of terrain `mesh` in the folder `rt-view bench --out`
    wrote; returns the scene file's path."""
    obj = os.path.join(bench_out, f"terrain_{mesh}.obj")
    with open(obj[:-4] + ".json") as f:
        cam = json.load(f)
    return rt_scene(bench_out, obj, cam)


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3):
        raise SystemExit(__doc__)
    print(terrain_scene(*sys.argv[1:]))
