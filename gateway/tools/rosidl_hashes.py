#!/usr/bin/env python3
"""The REP-2016 hashes rosidl computes for a package's published definitions, with the
venv's own rosidl: the steps of rosidl_generate_interfaces (rosidl_adapter turns each
.msg/.srv/.action into .idl, rosidl_generator_type_description hashes them with the venv's
installed packages as includes).

    $VENV/bin/python gateway/tools/rosidl_hashes.py PKG FILE... [--json-dir DIR]

PKG is the package name; each FILE is a `<dir>/<msg|srv|action>/<Name>.<ext>` of it (a
package may be given from several directories, e.g. Jazzy's FollowJointTrajectory.action
beside the shared .msg files). Prints `type_name hash` per structure; with --json-dir, also
writes rosidl's type-description JSON as it installs it (`DIR/<kind>/<Name>.json`).
"""
import argparse
import contextlib
import json
import shutil
import sys
import tempfile
from pathlib import Path

from rosidl_adapter.action import convert_action_to_idl
from rosidl_adapter.msg import convert_msg_to_idl
from rosidl_adapter.srv import convert_srv_to_idl
from rosidl_generator_type_description import generate_type_hash

CONVERT = {'.msg': convert_msg_to_idl, '.srv': convert_srv_to_idl,
           '.action': convert_action_to_idl}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument('package')
    ap.add_argument('files', nargs='+')
    ap.add_argument('--json-dir')
    a = ap.parse_args()
    share = Path(sys.prefix) / 'share'
    # the adapter reports each file it reads and writes on stdout
    with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(sys.stderr):
        out = Path(tmp) / 'idl'
        tuples = []
        for f in map(lambda f: Path(f).resolve(), a.files):
            pkg_dir = f.parent.parent
            p = CONVERT[f.suffix](pkg_dir, a.package, f.relative_to(pkg_dir), out)
            tuples.append(f'{out}:{p.relative_to(out)}')
        args = Path(tmp) / 'args.json'
        json_out = Path(tmp) / 'json'
        args.write_text(json.dumps({
            'package_name': a.package,
            'output_dir': str(json_out),
            'idl_tuples': tuples,
            'include_paths': [f'{d.name}:{d}' for d in share.iterdir() if d.is_dir()],
        }))
        hashes = set()
        for j in generate_type_hash(str(args)):
            j = Path(j)
            for h in json.loads(j.read_text())['type_hashes']:
                if h['type_name'].startswith(a.package + '/'):
                    hashes.add((h['type_name'], h['hash_string']))
            if a.json_dir:
                dest = Path(a.json_dir) / j.parent.name
                dest.mkdir(parents=True, exist_ok=True)
                shutil.copy(j, dest / j.name)
    for name, h in sorted(hashes):
        print(name, h)


if __name__ == '__main__':
    main()
