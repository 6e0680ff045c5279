#!/usr/bin/env python3
"""Renders the README's before/after pair of scenes/studio.json (issue 27):
docs/images/studio_before.png, the scene as rtcl could render it before issue 27
(a pinhole camera, point lights, no Fresnel term, each mesh the default material
whatever its file says), and docs/images/studio.png, the scene as it is.
Both 640x400 at 16 samples a pixel on rtcl's default device.

    /usr/bin/python3 tools/build/studio_images.py [RTCL]
"""
import json
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]


def before(scene):
    """The scene with issue 27's features turned off."""
    scene = json.loads(json.dumps(scene))
    for key in ("aperture", "focus_distance"):
        scene["camera"].pop(key, None)
    lights = []
    for light in scene["lights"]:
        light = {k: v for k, v in light.items() if k not in ("radius", "angle")}
        if "direction" in light:  # a point light far along the way it comes from
            d = light.pop("direction")
            light["position"] = [-100 * c for c in d]
        lights.append(light)
    scene["lights"] = lights
    for material in scene["materials"].values():
        material.pop("fresnel", None)
    for mesh in scene["meshes"]:
        mesh["file"] = str(ROOT / "scenes" / mesh["file"])
        mesh["material"] = {}  # the default material, as before issue 27
    return scene


def main():
    rtcl = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "rtcl")
    studio = ROOT / "scenes" / "studio.json"
    images = ROOT / "docs" / "images"
    with tempfile.TemporaryDirectory() as tmp:
        old = pathlib.Path(tmp) / "studio_before.json"
        old.write_text(json.dumps(before(json.loads(studio.read_text()))))
        for scene, image in ((old, "studio_before.png"), (studio, "studio.png")):
            subprocess.run([rtcl, "-s", str(scene), "-q", "-o", str(images / image)],
                           check=True)


if __name__ == "__main__":
    main()
