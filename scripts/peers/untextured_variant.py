#!/usr/bin/env python3
"""Writes an untextured (optionally metal-free) copy of a bundled glTF scene for the
side-by-side peers harness.

The harness (../shared/peers, `scene_gltf.py`) converts base-colour *factors* only, so a scene
with a base-colour texture (scenes/caustic-pool.gltf: the pool floor's tiles) would not be the
same scene for LuxCore / Mitsuba 3 as for chainlight. This replaces every `baseColorTexture` by
a constant factor (default 0.7 0.75 0.8, linear) and writes the copy, with its buffer, into
OUT_DIR; both chainlight and the peers then render the copy.

With `--matte-metals` every metallic material (metallicFactor > 0.5) becomes a diffuse one
with the same base colour (metallicFactor 0, roughness 1): the harness's conductor
(LuxCore `metal2` with a `fresnelcolor`) is not glTF's metal (Schlick with F0 = base colour),
which on scenes/glossy-highlight.gltf made LuxCore 9 % darker along the plate's reflection,
so a scene with metal is only comparable without it. The copy is named `<stem>-matte.gltf`.

    python3 scripts/peers/untextured_variant.py scenes/caustic-pool.gltf /tmp/peers/scenes
    python3 scripts/peers/untextured_variant.py --matte-metals scenes/ajar-door.gltf /tmp/peers/scenes
"""
import json, os, shutil, sys


def main():
    args = sys.argv[1:]
    matte = '--matte-metals' in args
    args = [a for a in args if a != '--matte-metals']
    if len(args) not in (2, 5):
        sys.exit('usage: untextured_variant.py [--matte-metals] SCENE.gltf OUT_DIR [R G B]')
    src, out = args[0], args[1]
    rgb = [float(x) for x in args[2:5]] if len(args) == 5 else [0.7, 0.75, 0.8]
    js = json.load(open(src))
    if matte:
        for m in js.get('materials', []):
            pbr = m.get('pbrMetallicRoughness', {})
            if pbr.get('metallicFactor', 1.0) > 0.5:
                pbr['metallicFactor'] = 0.0
                pbr['roughnessFactor'] = 1.0
    for m in js.get('materials', []):
        pbr = m.get('pbrMetallicRoughness', {})
        if 'baseColorTexture' in pbr:
            del pbr['baseColorTexture']
            pbr['baseColorFactor'] = rgb + [1.0]
    js.pop('textures', None); js.pop('images', None); js.pop('samplers', None)
    os.makedirs(out, exist_ok=True)
    for b in js.get('buffers', []):
        uri = b.get('uri', '')
        if uri and not uri.startswith('data:'):
            shutil.copy(os.path.join(os.path.dirname(src), uri), os.path.join(out, os.path.basename(uri)))
            b['uri'] = os.path.basename(uri)
    stem = os.path.splitext(os.path.basename(src))[0]
    dst = os.path.join(out, stem + ('-matte.gltf' if matte else '-untextured.gltf'))
    json.dump(js, open(dst, 'w'), indent=1)
    print(dst)


if __name__ == '__main__':
    main()
