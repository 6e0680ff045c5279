"""The names of a mesh file's materials (issue 39 finding 17; docs/SCENE.md,
"Materials from mesh files"): long names are kept whole, so that "materials"
takes the exact name and two names sharing a long beginning stay two; a name
the file does not have (the importer's stand-ins "DefaultMaterial" and glTF's
unnamed default "#N" included) is refused with the file's names and the nearest
suggested."""
import json

from test_mesh_materials import OBJ, quad, refused, render, scene

LONG = "m" * 150  # the two names share 150 bytes, more than the 127 kept before
RED, GREEN = LONG + "_red_" + "x" * 40, LONG + "_green_" + "x" * 40


def long_names(tmp_path, mesh):
    obj = OBJ.replace("usemtl red", f"usemtl {RED}").replace("usemtl green", f"usemtl {GREEN}")
    mtl = f"newmtl {RED}\nKd 0.9 0.1 0.1\nnewmtl {GREEN}\nKd 0.1 0.8 0.1\n"
    return scene(tmp_path, mesh, obj=obj, mtl=mtl)


def test_long_names_stay_whole_and_apart(tmp_path):
    """Before: the exact name was refused, and the two were one ("2 materials")."""
    path = long_names(tmp_path, {"materials": {RED: {"color": [0.1, 0.1, 0.9]}}})
    image, err = render(tmp_path, path, "-v")
    blue, green = quad(image, 0), quad(image, 2)
    assert blue[2] > blue[0] + 60, blue
    assert green[1] > 200 and green[0] < 110 and green[2] < 110, green
    assert '"quads.obj": 2 materials (2 used)' in err


def test_an_importer_stand_in_is_not_a_material_of_the_file(tmp_path):
    """Assimp's "DefaultMaterial" of an OBJ, which no triangle has: before, accepted
    with no effect."""
    path = scene(tmp_path, {"materials": {"DefaultMaterial": {"color": [0, 0, 1]}}})
    assert refused(tmp_path, path) == (
        f'{path}: meshes[0].materials: "quads.obj" has no material "DefaultMaterial"; its '
        'materials are "red", "green", "undefined"')


def test_gltf_unnamed_default_is_not_a_material_of_the_file(tmp_path):
    """Assimp appends a default material to a glTF's ("#1" here)."""
    import test_gltf_rules as g
    doc = g.triangle_gltf()
    doc["materials"] = [{"name": "paint", "pbrMetallicRoughness": {"baseColorFactor":
                                                                   [1, 0, 0, 1]}}]
    doc["meshes"][0]["primitives"][0]["material"] = 0
    (tmp_path / "m.gltf").write_text(json.dumps(doc))
    path = scene(tmp_path, {"materials": {"#1": {"color": [0, 0, 1]}}})
    doc = json.loads(path.read_text())
    doc["meshes"][0]["file"] = "m.gltf"
    path.write_text(json.dumps(doc))
    assert refused(tmp_path, path) == (
        f'{path}: meshes[0].materials: "m.gltf" has no material "#1"; its materials are'
        ' "paint"')


def test_a_mistyped_name_gets_the_nearest_suggested(tmp_path):
    path = scene(tmp_path, {"materials": {"rde": {"color": [0, 0, 1]}}})
    assert refused(tmp_path, path).endswith('its materials are "red", "green", "undefined";'
                                            ' did you mean "red"?')


def escaped_name_scene(tmp_path, materials):
    """A glTF quad whose material is named "pa<ESC>int"."""
    import test_gltf_rules as g
    doc = g.triangle_gltf()
    doc["materials"] = [{"name": "pa\x1bint", "pbrMetallicRoughness": {"baseColorFactor":
                                                                      [1, 0, 0, 1]}}]
    doc["meshes"][0]["primitives"][0]["material"] = 0
    (tmp_path / "m.gltf").write_text(json.dumps(doc))
    path = scene(tmp_path, {"materials": materials})
    doc = json.loads(path.read_text())
    doc["meshes"][0]["file"] = "m.gltf"
    path.write_text(json.dumps(doc))
    return path


def test_a_control_byte_in_a_material_name_is_shown_escaped(tmp_path):
    """GUIDE.md: a name read from a file shows its control bytes as \\x1b. Before:
    "pa?int", here and in the suggestion."""
    path = escaped_name_scene(tmp_path, {"paint": {"color": [0, 0, 1]}})
    assert refused(tmp_path, path) == (
        f'{path}: meshes[0].materials: "m.gltf" has no material "paint"; its materials are'
        ' "pa\\x1bint"; did you mean "pa\\x1bint"?')


def test_a_material_name_with_a_control_byte_is_taken_by_its_exact_name(tmp_path):
    """Before: the file's name was read as "pa?int", and its own name refused."""
    path = escaped_name_scene(tmp_path, {"pa\x1bint": {"color": [0, 0, 1]}})
    image, err = render(tmp_path, path)
    middle = quad(image, 1)
    assert middle[2] > middle[0] + 60, middle  # blue as the override, not the file's red
