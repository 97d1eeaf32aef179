#!/usr/bin/env python3
"""Stand-in shared libraries for the readers OpenImageIO links but no device
run uses: each defines exactly the symbols libOpenImageIO takes from the real
library (OpenImageIO binds at load, BIND_NOW), with the real library's symbol
versions, as functions that abort if ever called.
usage: stubs.py OUTDIR LIB..."""
import os, re, subprocess, sys

L = '/usr/lib/x86_64-linux-gnu'
out = sys.argv[1]
oiio = f'{L}/libOpenImageIO.so.2.4'
undef = set()
for line in subprocess.run(['nm', '-D', '--undefined-only', oiio], capture_output=True, text=True).stdout.splitlines():
    undef.add(line.split()[-1].split('@')[0])
for lib in sys.argv[2:]:
    syms = {}
    for line in subprocess.run(['nm', '-D', '--defined-only', f'{L}/{lib}'], capture_output=True, text=True).stdout.splitlines():
        parts = line.split()
        name, _, version = parts[-1].partition('@')
        version = version.lstrip('@')
        if name in undef and parts[1] in 'TtWiV':
            syms[name] = version
    c = ['#include <stdio.h>', '#include <stdlib.h>']
    for i, name in enumerate(sorted(syms)):
        c.append(f'void s{i}(void) __asm__("{name}");')
        c.append(f'void s{i}(void) {{ fprintf(stderr, "device stub called: {name}\\n"); abort(); }}')
    nodes = {}
    for name, version in syms.items():
        if version and version != 'Base':
            nodes.setdefault(version, []).append(name)
    src, vmap = f'{out}/{lib}.c', f'{out}/{lib}.map'
    open(src, 'w').write('\n'.join(c) + '\n')
    args = ['gcc', '-shared', '-fPIC', '-o', f'{out}/{lib}', src, f'-Wl,-soname,{lib}']
    if nodes:
        open(vmap, 'w').write(''.join(f'{v} {{ global: {"; ".join(n)}; }};\n' for v, n in nodes.items()))
        args.append(f'-Wl,--version-script={vmap}')
    subprocess.run(args, check=True)
    print(lib, len(syms), 'symbols', list(nodes))
