"""Serves a folder written by precomputed.py to neuroglancer's own Python viewer (its bundled
client, on 127.0.0.1) and prints one JSON line: for each view (the segmentation volume with its
unsharded mesh source; the sharded mesh source alone), the viewer's address with the segments
selected and with none. Then waits until standard input closes (tests/browser/neuroglancer.mjs
opens the addresses in headless Chromium meanwhile).

Usage: python ng_viewer.py DATA_DIR SEGMENTS(comma-separated)
"""
import json
import sys

import neuroglancer
import neuroglancer.static_file_server


def main():
    data, segments = sys.argv[1], [int(s) for s in sys.argv[2].split(",")]
    neuroglancer.set_server_bind_address("127.0.0.1")
    files = neuroglancer.static_file_server.StaticFileServer(data, bind_address="127.0.0.1", daemon=True)
    base = files.__enter__()
    views, keep = {}, []
    for name, source in (("unsharded", f"precomputed://{base}/seg"),
                         ("sharded", f"precomputed://{base}/seg/mesh_sharded")):
        for suffix, selected in (("", segments), (" (no segment)", [])):
            viewer = neuroglancer.Viewer()
            with viewer.txn() as s:
                s.dimensions = neuroglancer.CoordinateSpace(names=["x", "y", "z"], units="nm", scales=[1, 1, 1])
                s.position = [24, 20, 22]
                s.projection_scale = 96
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
