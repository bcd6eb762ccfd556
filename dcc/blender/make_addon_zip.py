#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes the installable Blender add-on zip: softbake_blender/*.py inside, ready for
Edit > Preferences > Add-ons > Install... or bpy.ops.preferences.addon_install(filepath=...).

    python3 dcc/blender/make_addon_zip.py OUT.zip

The zip is reproducible (sorted entries, fixed timestamps and permissions), so the same sources
give the same bytes, and it is written to a temporary name and renamed into place.
Python 3 standard library only.
"""

import argparse
import os
import sys
import tempfile
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
PACKAGE = "softbake_blender"
TIMESTAMP = (1980, 1, 1, 0, 0, 0)  # the earliest a zip can hold


def addon_files(source):
    files = []
    for root, dirs, names in os.walk(source):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__" and not d.startswith("."))
        for name in sorted(names):
            if name.endswith(".py"):
                path = os.path.join(root, name)
                files.append((path, os.path.relpath(path, source).replace(os.sep, "/")))
    return sorted(files, key=lambda f: f[1])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("output", help="the zip to write, e.g. build/dcc/softbake_blender.zip")
    parser.add_argument("--source", default=os.path.join(HERE, PACKAGE),
                        help="the add-on folder (default: %(default)s)")
    args = parser.parse_args(argv)

    source = os.path.abspath(args.source)
    files = addon_files(source)
    if not any(arc == "__init__.py" for _, arc in files):
        print("make_addon_zip: no __init__.py in '%s'" % source, file=sys.stderr)
        return 1

    output = os.path.abspath(args.output)
    os.makedirs(os.path.dirname(output), exist_ok=True)
    fd, temporary = tempfile.mkstemp(prefix=".softbake_blender.", suffix=".zip.tmp",
                                     dir=os.path.dirname(output))
    try:
        with os.fdopen(fd, "wb") as raw, zipfile.ZipFile(raw, "w", zipfile.ZIP_DEFLATED) as z:
            for path, arc in files:
                info = zipfile.ZipInfo(PACKAGE + "/" + arc, TIMESTAMP)
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = 0o100644 << 16
                with open(path, "rb") as f:
                    z.writestr(info, f.read())
        os.chmod(temporary, 0o644)
        os.replace(temporary, output)
    except BaseException:
        try:
            os.unlink(temporary)
        except OSError:
            pass
        raise
    print("make_addon_zip: wrote %s (%d files)" % (output, len(files)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
