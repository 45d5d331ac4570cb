"""One bilinear formula for every gridded sample: the met-ocean field and the planning grid."""

import numpy as np


def test_one_bilinear_sample_reproduces_a_bilinear_function_in_and_across_slices():
    """The met-ocean field, its time slices and the planning grid share one bilinear formula:
    a function a + b x + c y + d x y is reproduced to rounding anywhere in a cell (so a
    swapped weight, corner or sign shows), and slice ``k`` of a stack is the slice's own."""
    from rhnc.weather.metocean import bilinear

    x_nodes = np.array([0.0, 1.0, 2.0])
    y_nodes = np.array([0.0, 1.0, 2.0, 3.0])
    X, Y = np.meshgrid(x_nodes, y_nodes, indexing="ij")

    def exact(x, y):
        return 1.5 - 2.0 * x + 0.7 * y + 3.1 * x * y

    grid = exact(X, Y)
    rng = np.random.default_rng(5)
    px, py = rng.uniform(0, 2, 50), rng.uniform(0, 3, 50)
    i = np.minimum(np.floor(px).astype(int), 1)
    j = np.minimum(np.floor(py).astype(int), 2)
    np.testing.assert_allclose(bilinear(grid, i, j, px - i, py - j), exact(px, py), rtol=0, atol=1e-12)
    stack = np.stack([grid, 2 * grid, -grid])
    k = np.arange(50) % 3
    np.testing.assert_allclose(bilinear(stack, i, j, px - i, py - j, k),
                               np.array([1.0, 2.0, -1.0])[k] * exact(px, py), rtol=0, atol=1e-12)
