#!/usr/bin/env python3
"""The layering of src/ (docs/architecture.md), for meson.

  layers.py links BUILD_LAYERS_DIR SRC_DIR LAYER=USE,USE... ...
      Makes BUILD_LAYERS_DIR/LAYER/ hold one symbolic link per layer LAYER
      may use (USE -> SRC_DIR/USE). Each layer's library is compiled with
      -I BUILD_LAYERS_DIR/LAYER only, so '#include "can/socketcan.h"' in a
      layer that may not use can finds no such file.

  layers.py check OUTPUT DEPFILE SRC_DIR SANS_IO_LAYERS LAYER=USE,USE... ...
      Reads every '#include' of src/LAYER/*.[ch] and fails, naming file:line,
      on a quoted include of a layer LAYER may not use, on one that climbs out
      of its folder ('../'), and, in the sans-I/O layers (comma-separated),
      on any system header that is not part of the C standard library
      (sockets, file descriptors, clocks, threads). Writes OUTPUT (an empty
      header that the layers' libraries list, so nothing compiles before the
      check passed) and DEPFILE.
"""
import os
import re
import sys

# C11's headers, minus those that reach outside the process's memory
# (signal.h, threads.h, time.h: clocks are the caller's job in a sans-I/O layer)
C_STANDARD = {
    'assert.h', 'complex.h', 'ctype.h', 'errno.h', 'fenv.h', 'float.h',
    'inttypes.h', 'iso646.h', 'limits.h', 'locale.h', 'math.h', 'setjmp.h',
    'stdalign.h', 'stdarg.h', 'stdatomic.h', 'stdbool.h', 'stddef.h',
    'stdint.h', 'stdio.h', 'stdlib.h', 'stdnoreturn.h', 'string.h',
    'tgmath.h', 'uchar.h', 'wchar.h', 'wctype.h',
}

INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')


def parse_layers(args):
    layers = {}
    for a in args:
        name, _, uses = a.partition('=')
        layers[name] = [u for u in uses.split(',') if u]
    return layers


def links(build_dir, src_dir, layers):
    for layer, uses in layers.items():
        d = os.path.join(build_dir, layer)
        os.makedirs(d, exist_ok=True)
        for old in os.listdir(d):
            if old not in uses:
                os.unlink(os.path.join(d, old))
        for u in uses:
            link = os.path.join(d, u)
            target = os.path.relpath(os.path.join(src_dir, u), d)
            if os.path.islink(link) and os.readlink(link) == target:
                continue
            if os.path.lexists(link):
                os.unlink(link)
            os.symlink(target, link)
    return 0


def check(output, depfile, src_dir, sans_io, layers):
    problems = []
    read = [os.path.abspath(__file__)]
    for layer, uses in sorted(layers.items()):
        d = os.path.join(src_dir, layer)
        read.append(d)
        for name in sorted(os.listdir(d)):
            if not name.endswith(('.c', '.h')):
                continue
            path = os.path.join(d, name)
            read.append(path)
            shown = os.path.join('src', layer, name)
            with open(path, encoding='utf-8') as f:
                for lineno, line in enumerate(f, 1):
                    m = INCLUDE.match(line)
                    if not m:
                        continue
                    quote, header = m.groups()
                    where = f'{shown}:{lineno}: #include {quote}{header}{">" if quote == "<" else quote}'
                    if quote == '"':
                        top = header.split('/')[0] if '/' in header else layer
                        if header.startswith('../') or '/../' in header:
                            problems.append(f'{where}: climbs out of src/{layer}; name the header as "layer/file.h"')
                        elif top not in uses:
                            problems.append(f'{where}: layer {layer} may not use layer {top} '
                                            f'(it may use: {", ".join(uses)})')
                    elif layer in sans_io and header not in C_STANDARD:
                        problems.append(f'{where}: layer {layer} is sans-I/O and may include only '
                                        f'the C standard library')
    for p in problems:
        print(p, file=sys.stderr)
    if problems:
        print(f'{len(problems)} include(s) break the layering of src/: see docs/architecture.md',
              file=sys.stderr)
        return 1
    with open(output, 'w', encoding='utf-8') as f:
        f.write('/* src/layers.py check: the #includes of src/ keep to the layering */\n')
    with open(depfile, 'w', encoding='utf-8') as f:
        f.write(output.replace(' ', '\\ ') + ': ' + ' '.join(p.replace(' ', '\\ ') for p in read) + '\n')
    return 0


def main(argv):
    if len(argv) >= 3 and argv[0] == 'links':
        return links(argv[1], argv[2], parse_layers(argv[3:]))
    if len(argv) >= 5 and argv[0] == 'check':
        return check(argv[1], argv[2], argv[3], set(argv[4].split(',')), parse_layers(argv[5:]))
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
