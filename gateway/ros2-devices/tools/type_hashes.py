#!/usr/bin/env python3
"""Prints the REP-2016 hashes rosidl computes for robotology/yarp-devices-ros2's
yarp_control_msgs, the reference of tests/type_hashes.rs.

    ROS_VENV=... $ROS_VENV/bin/python tools/type_hashes.py PKG_DIR

PKG_DIR holds the package's msg/*.msg and srv/*.srv as published
(ros2_interfaces_ws/src/yarp_control_msgs). The same steps as rosidl_generate_interfaces:
rosidl_adapter turns them into .idl, rosidl_generator_type_description hashes them with the
venv's installed dependencies (builtin_interfaces, service_msgs, ...) as includes.
"""
import contextlib
import json
import sys
import tempfile
from pathlib import Path

from rosidl_adapter.msg import convert_msg_to_idl
from rosidl_adapter.srv import convert_srv_to_idl
from rosidl_generator_type_description import generate_type_hash


def main(pkg_dir: str) -> None:
    pkg = Path(pkg_dir).resolve()
    share = Path(sys.prefix) / 'share'
    # the adapter reports each file it reads and writes on stdout
    with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(sys.stderr):
        out = Path(tmp) / 'idl'
        tuples = []
        for f in sorted(pkg.glob('msg/*.msg')):
            p = convert_msg_to_idl(pkg, 'yarp_control_msgs', f.relative_to(pkg), out)
            tuples.append(f'{out}:{p.relative_to(out)}')
        for f in sorted(pkg.glob('srv/*.srv')):
            p = convert_srv_to_idl(pkg, 'yarp_control_msgs', f.relative_to(pkg), out)
            tuples.append(f'{out}:{p.relative_to(out)}')
        args = Path(tmp) / 'args.json'
        args.write_text(json.dumps({
            'package_name': 'yarp_control_msgs',
            'output_dir': str(Path(tmp) / 'json'),
            'idl_tuples': tuples,
            'include_paths': [f'{d.name}:{d}' for d in share.iterdir() if d.is_dir()],
        }))
        hashes = set()
        for j in generate_type_hash(str(args)):
            for h in json.loads(Path(j).read_text())['type_hashes']:
                if h['type_name'].startswith('yarp_control_msgs/'):
                    hashes.add((h['type_name'], h['hash_string']))
    for name, h in sorted(hashes):
        print(name, h)


if __name__ == '__main__':
    main(sys.argv[1])
