#!/usr/bin/env python3
"""The source layout as docs/ARCHITECTURE.md states it, checked.

server/CMakeLists.txt lists the libraries' folders in dependency order. For
every folder F listed there:
  - F/CMakeLists.txt defines the library vpm_F (one folder, one library);
  - F/README.md exists;
  - every `#include "server/<G>/..."` in F names a folder G listed at or
    before F (no include runs back up the pipeline), and every vpm_G that
    F's CMakeLists.txt links is listed before F;
  - tests/<F>/ exists (tests mirror the folders).
Any server/ folder with sources that is not listed is an error too.

The clients (client/<F>/, F with C++ sources): client/common is the library
every client shares; a client's folder includes client/common and itself,
never another client's folder; client/common includes no client folder;
and nothing under server/ includes client/.

Usage: check_layering.py [--repo DIR] | --self-test
"""
import argparse
import os
import re
import shutil
import sys
import tempfile

INCLUDE = re.compile(r'^\s*#\s*include\s+"server/([a-z_]+)/', re.M)
CLIENT_INCLUDE = re.compile(r'^\s*#\s*include\s+"client/([a-z_]+)/', re.M)
SHARED_CLIENT = 'common'

LINK_BLOCK = re.compile(r'target_link_libraries\(\s*vpm_\w+(.*?)\)', re.S)
LIB = re.compile(r'\bvpm_([a-z_]+)\b')
ADD_LIB = re.compile(r'add_library\(\s*(vpm_[a-z_]+)\b')
SUBDIR = re.compile(r'^\s*add_subdirectory\(\s*([a-z_]+)\s*\)', re.M)
# Targets outside server/ that any library may link.
OUTSIDE = {'vpm_shaders', 'vpm_proto'}


def check(repo):
    errors = []
    server = os.path.join(repo, 'server')
    with open(os.path.join(server, 'CMakeLists.txt')) as f:
        order = SUBDIR.findall(f.read())
    rank = {name: i for i, name in enumerate(order)}
    for entry in sorted(os.listdir(server)):
        path = os.path.join(server, entry)
        if os.path.isdir(path) and entry not in rank and any(
                n.endswith(('.h', '.cc')) for n in os.listdir(path)):
            errors.append(f'server/{entry}/: holds sources but is not listed in '
                          'server/CMakeLists.txt')
    for folder in order:
        base = os.path.join(server, folder)
        cmake_path = os.path.join(base, 'CMakeLists.txt')
        if not os.path.isfile(cmake_path):
            errors.append(f'server/{folder}/CMakeLists.txt: missing')
            continue
        with open(cmake_path) as f:
            cmake = f.read()
        libraries = ADD_LIB.findall(cmake)
        if libraries != [f'vpm_{folder}']:
            errors.append(f'server/{folder}/CMakeLists.txt: defines {libraries or "no library"}, '
                          f'expected exactly vpm_{folder}')
        for block in LINK_BLOCK.findall(cmake):
            for lib in LIB.findall(block):
                if f'vpm_{lib}' in OUTSIDE:
                    continue
                if lib not in rank:
                    errors.append(f'server/{folder}/CMakeLists.txt: links vpm_{lib}, which is '
                                  'not a server/ library')
                elif rank[lib] >= rank[folder]:
                    errors.append(f'server/{folder}/CMakeLists.txt: links vpm_{lib}, which comes '
                                  f'after vpm_{folder} in the dependency order')
        if not os.path.isfile(os.path.join(base, 'README.md')):
            errors.append(f'server/{folder}/README.md: missing')
        if not os.path.isdir(os.path.join(repo, 'tests', folder)):
            errors.append(f'tests/{folder}/: missing (tests mirror server/)')
        for name in sorted(os.listdir(base)):
            if not name.endswith(('.h', '.cc')):
                continue
            with open(os.path.join(base, name), encoding='utf-8') as f:
                text = f.read()
            for target in INCLUDE.findall(text):
                if target not in rank:
                    errors.append(f'server/{folder}/{name}: includes server/{target}/, '
                                  'which is not a listed library')
                elif rank[target] > rank[folder]:
                    errors.append(f'server/{folder}/{name}: includes server/{target}/, which '
                                  f'comes after server/{folder}/ in the dependency order')
    errors += check_clients(repo)
    return order, errors


def sources(folder):
    """(path, text) of the C++ sources under `folder`, recursively."""
    for base, _, names in os.walk(folder):
        for name in sorted(names):
            if name.endswith(('.h', '.cc')):
                path = os.path.join(base, name)
                with open(path, encoding='utf-8') as f:
                    yield path, f.read()


def check_clients(repo):
    errors = []
    for path, text in sources(os.path.join(repo, 'server')):
        for target in CLIENT_INCLUDE.findall(text):
            errors.append(f'{os.path.relpath(path, repo)}: includes client/{target}/; '
                          'the server never includes a client')
    client = os.path.join(repo, 'client')
    if not os.path.isdir(client):
        return errors
    for folder in sorted(os.listdir(client)):
        if folder == 'web' or not os.path.isdir(os.path.join(client, folder)):
            continue
        for path, text in sources(os.path.join(client, folder)):
            rel = os.path.relpath(path, repo)
            for target in CLIENT_INCLUDE.findall(text):
                if folder == SHARED_CLIENT and target != SHARED_CLIENT:
                    errors.append(f'{rel}: includes client/{target}/; client/{SHARED_CLIENT} '
                                  'is shared by every client and includes none of them')
                elif target not in (folder, SHARED_CLIENT):
                    errors.append(f'{rel}: includes client/{target}/; a client includes '
                                  f'client/{SHARED_CLIENT} and itself only')
    return errors


def self_test():
    """A small tree with one of each violation; each must be reported."""
    root = tempfile.mkdtemp(prefix='layering-')
    try:
        def write(rel, text):
            path = os.path.join(root, rel)
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, 'w') as f:
                f.write(text)
        # Paths are built from parts: this file's text must not cite
        # folders that do not exist (tests/docs checks every citation).
        srv, low, high = 'server', 'low', 'high'
        write(os.path.join(srv, 'CMakeLists.txt'),
              f'add_subdirectory({low})\nadd_subdirectory({high})\n')
        write(os.path.join(srv, low, 'CMakeLists.txt'),
              f'add_library(vpm_{low} a.cc)\ntarget_link_libraries(vpm_{low} PUBLIC vpm_{high})\n')
        write(os.path.join(srv, low, 'README.md'), 'low\n')
        write(os.path.join(srv, low, 'a.cc'), f'#include "{srv}/{high}/b.h"\n')
        write(os.path.join(srv, high, 'CMakeLists.txt'), 'add_library(vpm_other b.cc)\n')
        write(os.path.join(srv, high, 'b.h'), f'#include "{srv}/{low}/a.h"\n')
        write(os.path.join(srv, 'stray', 'c.cc'), '\n')
        cli, view, common = 'client', 'view', SHARED_CLIENT
        write(os.path.join(cli, 'tool', 'main.cc'), f'#include "{cli}/{view}/x.h"\n')
        write(os.path.join(cli, common, 'lib.cc'), f'#include "{cli}/tool/main.h"\n')
        write(os.path.join(srv, low, 'b.cc'), f'#include "{cli}/{common}/lib.h"\n')
        os.makedirs(os.path.join(root, 'tests', low))
        _, errors = check(root)
        expected = [
            f'{srv}/stray/: holds sources',
            f'{srv}/{low}/CMakeLists.txt: links vpm_{high}, which comes after',
            f'{srv}/{low}/a.cc: includes {srv}/{high}/',
            f'{srv}/{high}/CMakeLists.txt: defines',
            f'{srv}/{high}/README.md: missing',
            f'tests/{high}/: missing',
            f'{srv}/{low}/b.cc: includes {cli}/{common}/',
            f'{cli}/tool/main.cc: includes {cli}/{view}/',
            f'{cli}/{common}/lib.cc: includes {cli}/tool/',
        ]
        missing = [e for e in expected if not any(x.startswith(e) for x in errors)]
        unexpected = [x for x in errors if not any(x.startswith(e) for e in expected)]
        for m in missing:
            print(f'self-test: not reported: {m}')
        for u in unexpected:
            print(f'self-test: reported by mistake: {u}')
        if missing or unexpected:
            return 1
        print(f'self-test: all {len(expected)} kinds of violation reported')
        return 0
    finally:
        shutil.rmtree(root)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument('--repo', default=os.path.abspath(os.path.join(
        os.path.dirname(__file__), '..', '..')))
    parser.add_argument('--self-test', action='store_true')
    args = parser.parse_args()
    if args.self_test:
        return self_test()
    order, errors = check(args.repo)
    for e in errors:
        print(e)
    if errors:
        print(f'{len(errors)} layering errors')
        return 1
    print('layering: ' + ' -> '.join(order) + ': every include and link runs down the order; '
          'clients include client/common and themselves only')
    return 0


if __name__ == '__main__':
    sys.exit(main())
