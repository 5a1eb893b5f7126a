"""Run the bundled wall scene from Python and read the results with xarray.

    python examples/wall_push_api.py
"""
import numpy as np

import masonrydam
from masonrydam.cli.main import default_scene_path

ds = masonrydam.run(default_scene_path(), output="wall_push.nc", summary=True)

top = np.isclose(ds.y, ds.y.max())
H = ds.reaction.sel(component="x").where(top).sum("node")          # lateral force at the top beam, N
u = ds.displacement.sel(component="x").where(top).mean("node")    # top displacement, m
for step in range(ds.sizes["step"]):
    print(f"step {step:3d}  stage {int(ds.stage[step])}  u_top = {1e3 * float(u[step]):7.4f} mm  H = {1e-3 * float(H[step]):8.3f} kN")

last = ds.joint_state.isel(step=-1)
names = __import__("json").loads(ds.joint_set.attrs["set_names"])
for k, name in enumerate(names):
    sel = last.where(ds.joint_set == k, drop=True)
    print(f"{name:12s}: {int((sel == 0).sum())} stick, {int((sel == 1).sum())} slip, {int((sel == 2).sum())} open")
