"""isolab.marching_cubes(method='lewiner') (isolab's marching-cubes-33) against scikit-image's
Lewiner, cell by cell.

Both mesh each cell from its eight corner values alone, so every cell is compared on its own:
the volume's cells are spread apart (cell (i, j, k) becomes the block at (2i, 2j, 2k) of a
volume twice the size) and a mask keeps only those blocks, so each triangle belongs to the block
it lies in, even one lying in a face of the cell. A cell is the same when both make as many
triangles and both or neither add a vertex inside it. Every other cell must be one of these
named differences, judged against the trilinear interpolant's own level set in the cell (sampled
finely and meshed by scikit-image's Lorensen, an independent reference):

- LEWINER_ERRS: scikit-image's topology (components and their Euler characteristics) is not the
  interpolant's and ours is. Lewiner et al. decide a tunnel from one slice of the cell, which
  Custodio et al. 2013 show errs; isolab's interior test is exact.
- TUBE_RETILED: both are the interpolant's tube, drawn otherwise: ours took another of its
  tube triangulations (a band with a run fanned around the centre vertex, a band through the
  tunnel's waist ring, or the fan's vertex moved off Lewiner's centre), as it does where the
  first would cross itself at the cell's vertices; the one taken does not (checked).
- CRITICAL: the interpolant is within a hair of a critical value (a shift of the level by a
  small fraction of the corner values, or a finer sampling, changes its topology): neither can
  be judged.

Any other difference fails the test, with the cell's corner values. The rules are in
`lewiner_cells.py`, which the `real_volumes` experiment also runs on the report's scans.
"""

import os

import numpy as np
import pytest

from lewiner_cells import CRITICAL, LEWINER_ERRS, named_differences


def classified(vol, level):
    counts, unnamed = named_differences(vol, level)
    if unnamed:
        pytest.fail("\n".join(unnamed[:10]))
    return counts


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_grids_equal_scikit_images_lewiner_but_for_named_cells(seed):
    vol = np.random.default_rng(seed).random((13, 12, 11))  # every cell pattern, many ambiguous
    counts = classified(vol, 0.5)
    assert counts["same"] > 0.95 * sum(v for k, v in counts.items() if k != "same, with a centre"), counts
    # Random data has tunnels, and cells where scikit-image's one-slice test misses them.
    assert counts[LEWINER_ERRS] > 0, counts
    assert counts[CRITICAL] < 0.01 * counts["same"], counts


MRI = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tests", "reference", "volumes")


@pytest.mark.parametrize("level", [40.5, 90.5, 140.5])
def test_the_mri_fixture_equals_scikit_images_lewiner_but_for_named_cells(level):
    # tests/reference/volumes: the MNI template every 5th voxel, big-endian uint16, x fastest.
    raw = np.fromfile(os.path.join(MRI, "mni-small.raw"), dtype=">u2").reshape(38, 47, 40).transpose(2, 1, 0)
    counts = classified(raw.astype(np.float32), level)
    assert counts["same"] > 0.99 * sum(v for k, v in counts.items() if k != "same, with a centre"), counts
