#!/usr/bin/env python3
"""Writes the malformed scene corpus tests/data/scenes/bad/ (also the fuzzing seeds). Each file
starts with "# expect: TEXT", the text its error must contain; tests/scene/test_scene_corpus.cpp
loads each one and checks that the error names the file and a line:column too. Deterministic: run
it again and git sees no change."""
import os

HERE = os.path.dirname(os.path.abspath(__file__))
EMITTER = '[[emitter]]\ntype = "pour"\ncount = 1000\nrate = 500\ncenter = [0, 0, 0.5]\n'
FLOOR = '[[geometry]]\ntype = "plane"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n'
VALID = ('[scene]\nname = "floor"\n\n[material]\ndensity = 2600\ndiameter = 0.01\n\n'
         '[simulation]\nmode = "surface"\n\n' + FLOOR + '\n' + EMITTER)

CASES = {
    # truncated files
    "truncated_in_string.toml": ("Error while parsing string: encountered end-of-file", VALID[:VALID.index('oor"')]),
    "truncated_in_table_header.toml": ("Error while parsing table header: encountered end-of-file", VALID[:VALID.index("[simulation]") + 5]),
    "truncated_after_equals.toml": ("encountered end-of-file", "[material]\ndensity ="),
    "empty.toml": ("a scene needs at least one [[emitter]] table, found none", ""),
    # absurd counts and sizes
    "grains_10_12.toml": ("emitter[0].count = 1000000000000 is outside [1, 2000000000]",
                          EMITTER.replace("count = 1000", "count = 1_000_000_000_000")),
    "grains_10_12_as_float.toml": ("emitter[0].count = 1000000000000 is outside [1, 2000000000]",
                                   EMITTER.replace("count = 1000", "count = 1e12")),
    "grains_total_over_limit.toml": ("brings the scene to 3000000000 grains, more than the limit of "
                                     "2000000000 in all",
                                     (EMITTER.replace("count = 1000", "count = 1_000_000_000")) * 3),
    "count_beyond_int64.toml": ("is not representable in 64 bits", EMITTER.replace("count = 1000", "count = 99999999999999999999")),
    "grid_10_9_cells.toml": ("makes a height field of 33334 x 33334 columns, more than the limit of "
                             "16777216",
                             "[surface]\nextent = [0, 0, 1000, 1000]\ncell_size = 0.03\n\n" + EMITTER),
    "grid_default_cell.toml": ("(the grain diameter: cell_size unset) makes a height field of 100000 x "
                               "100000 columns",
                               "[material]\ndiameter = 0.01\n[surface]\nextent = [-500, -500, 500, 500]\n\n"
                               + EMITTER),
    "heights_one_row.toml": ("geometry[0].heights has 1 rows: expected 2 to 4096",
                             '[[geometry]]\ntype = "heightmap"\nextent = [0, 0, 1, 1]\n'
                             'heights = [[0, 1, 2]]\n\n' + EMITTER),
    "heights_ragged.toml": ("every row must have the same length",
                            '[[geometry]]\ntype = "heightmap"\nextent = [0, 0, 1, 1]\n'
                            'heights = [[0, 1, 2], [3, 4]]\n\n' + EMITTER),
    # emitters that no count makes possible (before these, `run --check --mode dem` hung on them)
    "pour_radius_1000m_of_1mm_grains.toml": ("emitter[0].radius makes a pour of about 3.29e+12 slots "
                                             "0.00105 m apart, more than the limit of 16777216",
                                             "[material]\ndiameter = 0.001\n\n" + EMITTER
                                             + "radius = 1000\n"),
    "emitter_center_1e308.toml": ("emitter[0].center reaches 1.7e+308 m from the origin",
                                  '[[emitter]]\ntype = "block"\ncount = 10\n'
                                  'center = [1.7e308, 0, 1]\nsize = [0.1, 0.1, 0.1]\n'),
    "block_thinner_than_a_grain.toml": ("emitter[0].size is 0.005 m along x, less than the largest "
                                        "grain (0.01 m)",
                                        '[[emitter]]\ntype = "block"\ncount = 10\n'
                                        'center = [0, 0, 50]\nsize = [0.005, 100, 100]\n'),
    # NaN and infinity
    "nan_friction.toml": ("material.friction = nan is not a finite number",
                          "[material]\nfriction = nan\n\n" + EMITTER),
    "inf_gravity.toml": ("simulation.gravity[2] = -inf is not a finite number",
                         "[simulation]\ngravity = [0, 0, -inf]\n\n" + EMITTER),
    "nan_in_heights.toml": ("geometry[0].heights[1][0] = nan is not a finite number",
                            '[[geometry]]\ntype = "heightmap"\nextent = [0, 0, 1, 1]\n'
                            'heights = [[0, 1], [nan, 1]]\n\n' + EMITTER),
    "inf_count.toml": ("emitter[0].count = inf is not a finite number",
                       EMITTER.replace("count = 1000", "count = inf")),
    # negative radii and diameters
    "negative_sphere_radius.toml": ("geometry[0].radius = -1 is not > 0",
                                    '[[geometry]]\ntype = "sphere"\ncenter = [0, 0, 0]\nradius = -1\n\n'
                                    + EMITTER),
    "negative_diameter.toml": ("material.diameter = -0.01 is not > 0",
                               "[material]\ndiameter = -0.01\n\n" + EMITTER),
    "nozzle_without_velocity.toml": ('emitter[0].facing = "velocity" lays the area across the '
                                     'velocity, but velocity is zero',
                                     EMITTER + 'facing = "velocity"\n'),
    "zero_pour_radius.toml": ("emitter[0].radius = 0 is not > 0",
                              EMITTER + "radius = 0\n"),
    # wrong types
    "string_for_number.toml": ('material.density: expected a number, got a string',
                               '[material]\ndensity = "heavy"\n\n' + EMITTER),
    "number_for_table.toml": ("material: expected a table [material], got an integer",
                              "material = 5\n\n" + EMITTER),
    "number_for_emitters.toml": ("emitter: expected an array of tables [[emitter]], got an integer",
                                 "emitter = 3\n"),
    "array_for_vector_of_2.toml": ("simulation.gravity: expected an array of 3 numbers, got 2 elements",
                                   "[simulation]\ngravity = [0, -9.81]\n\n" + EMITTER),
    "bool_for_string.toml": ('simulation.mode: expected one of "surface", "dem", got a boolean',
                             "[simulation]\nmode = true\n\n" + EMITTER),
    "date_for_number.toml": ("output.fps: expected a number, got a date",
                             "[output]\nfps = 1979-05-27\n\n" + EMITTER),
    "fraction_for_count.toml": ("emitter[0].count: expected an integer, got 1.5",
                                EMITTER.replace("count = 1000", "count = 1.5")),
    "unknown_choice.toml": ('simulation.mode = "fast" is not one of "surface", "dem"',
                            '[simulation]\nmode = "fast"\n\n' + EMITTER),
    # out of range
    "restitution_above_one.toml": ("material.restitution = 1.4 is outside (0, 1]",
                                   "[material]\nrestitution = 1.4\n\n" + EMITTER),
    "repose_angle_95.toml": ("surface.repose_angle = 95 is outside (0, 90)",
                             "[surface]\nrepose_angle = 95\n\n" + EMITTER),
    "threads_million.toml": ("simulation.threads = 1000000 is outside [0, 4096]",
                             "[simulation]\nthreads = 1_000_000\n\n" + EMITTER),
    # keys
    "unknown_key.toml": ("material.densty is not a key of [material]",
                         "[material]\ndensty = 2600\n\n" + EMITTER),
    "unknown_table.toml": ("materials is not a key of a scene file", "[materials]\ndensity = 1\n\n" + EMITTER),
    "duplicate_key.toml": ("cannot redefine existing", "[material]\ndensity = 2600\ndensity = 2700\n\n"
                           + EMITTER),
    "duplicate_table.toml": ("cannot redefine existing", "[material]\ndensity = 2600\n[material]\n"
                             "friction = 0.5\n\n" + EMITTER),
    "no_emitter.toml": ("a scene needs at least one [[emitter]] table, found none", "[material]\ndensity = 2600\n"),
    "count_missing.toml": ("emitter[0].count is missing", '[[emitter]]\ntype = "pour"\nrate = 10\n'),
    "key_of_another_type.toml": ("geometry[0].radius is not a key of a plane", FLOOR + "radius = 1\n\n" + EMITTER),
    "two_height_sources.toml": ("a heightmap takes exactly one of heights, file, noise",
                                '[[geometry]]\ntype = "heightmap"\nextent = [0, 0, 1, 1]\n'
                                'heights = [[0, 1], [2, 3]]\nfile = "h.png"\n\n' + EMITTER),
    # what the TOML library itself cannot be given safely (see toml_hazard in scene/toml_guard.cpp)
    "dotted_key_20_parts.toml": ("a dotted key or table name of more than 16 parts",
                                 ".".join(["material"] + ["a"] * 19) + " = 1\n\n" + EMITTER),
    "table_header_20_parts.toml": ("a dotted key or table name of more than 16 parts",
                                   "[" + ".".join(["t"] * 20) + "]\n\n" + EMITTER),
    "arrays_nested_300_deep.toml": ("exceeded maximum nested value depth of 256",
                                    "[simulation]\ngravity = " + "[" * 300 + "]" * 300 + "\n\n" + EMITTER),
    "non_ascii_key.toml": ("a non-ASCII character outside a string or comment",
                           "[material]\ndensit\u00e9 = 2600\n\n" + EMITTER),
    # found by fuzzing: toml++ reads on past a quote inside a malformed value, outside any string
    "non_ascii_after_value.toml": ("a non-ASCII character outside a string or comment",
                                   "[simulation]\nmode = 1'\u0396'\n\n" + EMITTER),
    "non_ascii_after_line_backslash.toml": ("a non-ASCII character after a backslash in a multi-line "
                                            "string",
                                            '[scene]\ndescription = """\\\n\u00a7 sand"""\n\n' + EMITTER),
    # values each in its type's range that the rest of the scene makes meaningless
    "restitution_below_the_laws_least.toml": ("material.restitution = 1e-06 is below 9.98e-05",
                                              "[material]\nrestitution = 1e-6\n\n" + EMITTER),
    "vdb_voxel_finer_than_d_over_200.toml": ("output.vdb_voxel_size = 1e-05 m is below 5e-05 m",
                                             "[output]\nvdb_voxel_size = 1e-5\n\n" + EMITTER),
    "wall_thickness_without_container.toml": ("geometry[0].wall_thickness belongs to a container",
                                              '[[geometry]]\ntype = "box"\ncenter = [0, 0, 0]\n'
                                              'size = [1, 1, 0.1]\nwall_thickness = 0.02\n\n'
                                              + EMITTER),
    # binary garbage and bad encodings
    "binary_garbage.toml": ("a non-ASCII character outside a string or comment", bytes((i * 131 + 17) % 256 for i in range(400))),
    "nul_bytes.toml": ("expected digit, saw '\\u0000'", "[material]\ndensity = 26\0\x0000\n\n" + EMITTER),
    "invalid_utf8_in_string.toml": ("invalid utf-8 sequence", b'[scene]\nname = "\xff\xfe"\n\n' + EMITTER.encode()),
    "control_char_in_string.toml": ("control characters", '[scene]\nname = "a\x07b"\n\n' + EMITTER),
}


def main():
    for name, (expect, body) in CASES.items():
        head = ("# expect: " + expect + "\n").encode()
        data = head + (body if isinstance(body, bytes) else body.encode())
        with open(os.path.join(HERE, "bad", name), "wb") as f:
            f.write(data)


if __name__ == "__main__":
    main()
