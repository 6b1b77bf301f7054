"""What ctsurg-render makes of one render request, for both pipelines.

A scenario's `render:` list (read back by `ctsurg-sim --describe`) names pictures by layout; this module
is the one mapping from a request (layout, frames, view, size, reference) to the files it makes and
ctsurg-render's options. scripts/scenario-mk.py (the Make pipeline's fragments) and scripts/Snakefile
both call it, so the two pipelines make the same pictures under the same names:

  layout single | side-by-side | overlay | heat-map, one frame   -> OUT/<name>.png
  the same with several frames ("all", "A:B", "A:B:STEP", "N,M")  -> OUT/<name>/<name>_<frame>.png, listed
                                                                     in OUT/<name>.frames (the target)
  layout viewer                                                    -> OUT/<name>.glb and OUT/<name>.html
                                                                     (the frames as an animated glTF and the
                                                                     offline page that plays it)
"""

MULTI = (",", ":")


def render_plan(request, out_dir, trajectory, surface=None, reference=None):
    """The request's files and ctsurg-render options (a list, without the program, -q and the
    patient's RENDER_ARGS). surface: the surface file to draw (None: the trajectory's own triangles, an
    FEM run without model.surface or a vessel); reference: the comparison's file (None: the rest
    surface). Returns dict(kind: picture | frames | viewer, outputs: [files the rule makes], args,
    folder and listing (frames only))."""
    name = request["name"]
    frames = str(request.get("frames", "last"))
    base = (["--surface", surface] if surface else []) + ["--trajectory", trajectory]
    if request["layout"] == "viewer":
        html, glb = f"{out_dir}/{name}.html", f"{out_dir}/{name}.glb"
        return dict(kind="viewer", outputs=[html, glb], folder=None, listing=None,
                    args=base + ["--frames", frames, "--gltf", glb, "--viewer", html])
    args = base + ["--layout", request["layout"], "--frames", frames, "--view", str(request["view"]),
                   "--size", str(int(request["size"]))]
    if reference:
        args += ["--reference", reference]
    if frames == "all" or any(c in frames for c in MULTI):
        folder, listing = f"{out_dir}/{name}", f"{out_dir}/{name}.frames"
        return dict(kind="frames", outputs=[listing], folder=folder, listing=listing,
                    args=args + ["-o", f"{folder}/{name}_{{}}.png"])
    png = f"{out_dir}/{name}.png"
    return dict(kind="picture", outputs=[png], folder=None, listing=None, args=args + ["-o", png])
