"""Serves a folder written by precomputed.py to neuroglancer's own Python viewer (its bundled
client, on 127.0.0.1) and prints one JSON line: for each view (the segmentation volume with its
unsharded mesh source; the sharded mesh source alone), the viewer's address with the segments
selected and with none. Then waits until standard input closes (tests/browser/neuroglancer.mjs
opens the addresses in headless Chromium meanwhile).

Usage: python ng_viewer.py DATA_DIR SEGMENTS(comma-separated) [NAME=PATH ...] [POS=x,y,z] [SCALE=s]
(views: each a precomputed source at PATH under DATA_DIR, in nanometres; by default "unsharded=seg" and
"sharded=seg/mesh_sharded"; POS the view's centre and SCALE its projection scale, in nanometres)
"""
import json
import sys

import neuroglancer
import neuroglancer.static_file_server


def main():
    data, segments = sys.argv[1], [int(s) for s in sys.argv[2].split(",")]
    settings = dict(a.split("=", 1) for a in sys.argv[3:] if a.split("=", 1)[0] in ("POS", "SCALE"))
    named = [a.split("=", 1) for a in sys.argv[3:] if a.split("=", 1)[0] not in ("POS", "SCALE")]
    named = named or [["unsharded", "seg"], ["sharded", "seg/mesh_sharded"]]
    position = [float(v) for v in settings.get("POS", "24,20,22").split(",")]
    scale = float(settings.get("SCALE", "96"))
    neuroglancer.set_server_bind_address("127.0.0.1")
    files = neuroglancer.static_file_server.StaticFileServer(data, bind_address="127.0.0.1", daemon=True)
    base = files.__enter__()
    views, keep = {}, []
    for name, path in named:
        source = f"precomputed://{base}/{path}"
        for suffix, selected in (("", segments), (" (no segment)", [])):
            viewer = neuroglancer.Viewer()
            with viewer.txn() as s:
                s.dimensions = neuroglancer.CoordinateSpace(names=["x", "y", "z"], units="nm", scales=[1, 1, 1])
                s.position = position
                s.projection_scale = scale
                s.projection_orientation = [0.3, 0.2, 0.1, 0.93]
                s.show_slices = False
                s.layout = "3d"
                s.layers["isolab"] = neuroglancer.SegmentationLayer(source=source, segments=selected)
            keep.append(viewer)
            views[name + suffix] = viewer.get_viewer_url()
    print(json.dumps(views), flush=True)
    sys.stdin.read()


if __name__ == "__main__":
    main()
