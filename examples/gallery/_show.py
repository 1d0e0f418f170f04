"""Show a PNG rendered by Ramure in the gallery (matplotlib collects the figure)."""

import tempfile

import matplotlib.image as mpimg
import matplotlib.pyplot as plt


def show(render, *args, **kwargs):
    """Call ``render(..., path, ...)`` into a temporary PNG and show it without axes."""
    with tempfile.TemporaryDirectory() as folder:
        path = f"{folder}/picture.png"
        render(*args, path, **kwargs)
        image = mpimg.imread(path)
    height, width = image.shape[:2]
    square = 0.8 < height / width < 1.25
    fig, ax = plt.subplots(figsize=(5, 5) if square else (8, min(8 * height / width, 24)))  # contact sheets stay readable
    ax.imshow(image)
    ax.set_axis_off()
    fig.tight_layout()
    return fig
