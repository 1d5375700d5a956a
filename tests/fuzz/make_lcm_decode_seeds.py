#!/usr/bin/env python3
"""Writes the seed corpus of fuzz_lcm_decode: for each LCM type it decodes, one encoded message
with empty arrays and one with two elements per array (and short strings), each behind the
selector byte that picks its type in fuzz_lcm_decode.cc. Encoded with lcm-gen's Python output of
protocols/lcm/*.lcm, generated into a temporary folder (no Python LCM module is needed).

Usage: tests/fuzz/make_lcm_decode_seeds.py [OUT_DIR]   (default tests/fuzz/seeds/fuzz_lcm_decode)
"""
import importlib
import os
import re
import subprocess
import sys
import tempfile

# The order of fuzz_lcm_decode.cc's switch (data[0] % 11).
TYPES = ["selfcal.joint_state_t", "selfcal.range_scan_t", "selfcal.line_profile_t",
         "selfcal.depth_image_t", "selfcal.organized_cloud_t", "selfcal.scan_marker_t",
         "selfcal.calibration_request_t", "selfcal.calibration_status_t",
         "selfcal.calibration_result_t", "drake.lcmt_iiwa_status", "drake.lcmt_iiwa_command"]
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def element(type_name):
    if type_name == "string":
        return "ab"
    if type_name in ("float", "double"):
        return 0.5
    if type_name == "boolean":
        return True
    if type_name in ("int8_t", "int16_t", "int32_t", "int64_t", "byte"):
        return 1
    raise ValueError("no seed value for a field of type " + type_name)


def fields(lcm_source):
    """(type, name, dimensions) of each field of the struct in an .lcm file."""
    text = re.sub(r"//[^\n]*|/\*.*?\*/", "", open(lcm_source).read(), flags=re.S)
    body = text[text.index("{") + 1:text.rindex("}")]
    result = []
    for declaration in body.split(";"):
        words = declaration.split()
        if len(words) < 2 or words[0] == "const":
            continue
        name, *dims = re.split(r"[\[\]]+", "".join(words[1:]).rstrip("]"))
        result.append((words[0], name, dims))
    return result


def filled(message, declared, count):
    """Sets every length field to `count`, every array to that many elements, strings short."""
    for kind, name, dims in declared:
        for size in dims:
            if not size.isdigit():
                setattr(message, size, count)
    for kind, name, dims in declared:
        if dims:
            value = element(kind)
            for size in reversed(dims):
                n = int(size) if size.isdigit() else count
                value = [value if not isinstance(value, list) else list(value) for _ in range(n)]
            setattr(message, name, value)
        elif kind == "string":
            setattr(message, name, "ab" if count else "")
    return message


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "tests/fuzz/seeds/fuzz_lcm_decode")
    os.makedirs(out, exist_ok=True)
    with tempfile.TemporaryDirectory() as generated:
        sources = [os.path.join(ROOT, "protocols/lcm", f) for f in sorted(os.listdir(
            os.path.join(ROOT, "protocols/lcm"))) if f.endswith(".lcm")]
        subprocess.run(["lcm-gen", "--python", "--ppath", generated] + sources, check=True,
                       stdout=subprocess.DEVNULL)
        sys.path.insert(0, generated)
        for selector, full_name in enumerate(TYPES):
            package, name = full_name.split(".")
            cls = getattr(importlib.import_module(package + "." + name), name)
            declared = fields(os.path.join(ROOT, "protocols/lcm", name + ".lcm"))
            for count in (0, 2):
                body = filled(cls(), declared, count).encode()
                path = os.path.join(out, "%s-%d.bin" % (name, count))
                with open(path + ".tmp", "wb") as f:
                    f.write(bytes([selector]) + body)
                os.replace(path + ".tmp", path)


if __name__ == "__main__":
    main()
