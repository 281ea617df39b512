"""How deep fluid particle centres get into a coupled structure's cross-section, frame by frame.

Reads a run's record.h5: the interface mesh (/interface/vertices, /cells), its displacement at the window
that ends on each frame, and the fluid's frames. For every fluid centre inside a cell it takes the distance
to the nearer of the cell's bottom and top edges (the beam's faces: structure/src/interface.cpp lays a cell
out as bottom_i, bottom_i+1, top_i+1, top_i) and prints the deepest over the run, in metres and in spacings.
The fluid's own check (fluid/include/sphfsi/fluid/solid_section.hpp) was chosen from these numbers.
usage: /usr/bin/python3 docs/validation/section_penetration.py RUN_DIR
(frames only: run with a short run.output_interval to see more of the run)
"""
import sys

import h5py
import numpy as np


def main(run_dir):
    with h5py.File(f"{run_dir}/record.h5", "r", locking=False) as f:
        dp = float(f["participants/fluid"].attrs["dp"])
        vertices, cells = f["interface/vertices"][:], f["interface/cells"][:]
        window_t, displacement = f["windows/t"][:], f["interface/displacement"]
        deepest, where = 0.0, None
        for k, t in enumerate(f["frames/fluid/time"][:]):
            shift = np.zeros_like(vertices) if t == 0 else displacement[int(np.argmin(abs(window_t - t)))]
            x = vertices + shift
            fluid = f["frames/fluid/position"][k][f["frames/fluid/kind"][k][:, 0] == 0]
            for cell in cells:
                q = x[cell]
                near = fluid[((fluid >= q.min(0)) & (fluid <= q.max(0))).all(1)]
                if not len(near):
                    continue
                inside = np.ones(len(near), dtype=bool)
                distance = []
                for i in range(4):  # signed distance from each edge, positive inside (counter-clockwise)
                    a, e = q[i], q[(i + 1) % 4] - q[i]
                    n = np.array([-e[1], e[0]]) / np.linalg.norm(e)
                    distance.append((near - a) @ n)
                    inside &= distance[-1] >= 0
                if inside.any():
                    depth = np.minimum(distance[0], distance[2])[inside]
                    if depth.max() > deepest:
                        deepest, where = float(depth.max()), float(t)
    print(f"deepest fluid centre inside the cross-section: {deepest:.3g} m = {deepest / dp:.2f} dp"
          + (f" (t = {where:.4g} s)" if where is not None else " (none inside)"))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
