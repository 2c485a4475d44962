"""The README's image, docs/img/slotting_tracking_error.png: the tracking error per axis of
the slotting job, from its offline run (the distributed run equals it bit for bit).

    python -m mill_bringup.docs_figures.image [--root .]

Writes the PNG and, beside it, slotting_tracking_error.json: what the plot shows, per axis
the minimum and maximum of e over every 0.5 s [µm, 4 digits]. The PNG carries the JSON's
sha256 in its metadata. A test re-runs the job and compares the JSON (the data: robust,
readable in a diff) and checks that the PNG was drawn from that JSON (its hash); pixels
are not compared, since they change with the matplotlib version and its fonts.
"""

from __future__ import annotations

import argparse
import hashlib
import json
from pathlib import Path

import numpy as np

from mill_bringup.docs_figures.runs import offline

SCENARIO = 'slotting'
IMAGE = Path('docs/img/slotting_tracking_error.png')
DATA = IMAGE.with_suffix('.json')
BIN = 0.5  # [s] of the digest
SKIP = 1.0  # [s] greyed in the plot, as the report does
HASH_KEY = 'Description'  # PNG text chunk holding 'data sha256 HEX'


def digest(rec) -> dict[str, object]:
    """Per axis, the min and max of e over each BIN seconds [µm, 4 significant digits]."""
    edges = np.searchsorted(rec.t, np.arange(0.0, rec.t[-1], BIN))
    out: dict[str, object] = {'scenario': SCENARIO, 'bin_s': BIN, 'samples': int(rec.t.size)}
    for i, axis in enumerate('xyz'):
        e = rec.tracking_error[:, i] * 1e6
        lo, hi = np.minimum.reduceat(e, edges), np.maximum.reduceat(e, edges)
        out[f'{axis}_min_um'] = [float(f'{v:.4g}') for v in lo]
        out[f'{axis}_max_um'] = [float(f'{v:.4g}') for v in hi]
    return out


def data_text(rec) -> str:
    return json.dumps(digest(rec), indent=None, separators=(',', ':')) + '\n'


def png_data_hash(path: Path) -> str | None:
    """The data hash the PNG was drawn from (None if it carries none)."""
    from PIL import Image

    with Image.open(path) as im:
        text = im.info.get(HASH_KEY, '')
    return text.removeprefix('data sha256 ') if text.startswith('data sha256 ') else None


def write(root: Path) -> None:
    from mill_analysis.report import plots

    rec = offline(SCENARIO)
    text = data_text(rec)
    (root / DATA).write_text(text, encoding='utf-8')
    plt = plots.styled_pyplot()
    fig = plots.axis_grid_figure(
        [SCENARIO],
        ['x', 'y', 'z'],
        'Tracking error per axis',
        lambda a, _c, i: plots.draw_tracking_error(a, rec.t, rec.tracking_error[:, i], SKIP),
    )
    sha = hashlib.sha256(text.encode()).hexdigest()
    fig.savefig(root / IMAGE, metadata={HASH_KEY: f'data sha256 {sha}'})
    plt.close(fig)
    print(f'wrote {root / IMAGE} and {root / DATA}')


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog='python -m mill_bringup.docs_figures.image')
    parser.add_argument('--root', type=Path, default=Path('.'), help='the repository (.)')
    write(parser.parse_args(argv).root)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
