"""An image stack (PNG, or TIFF through Pillow) turned into a voxel-id array
that scenes and cells read (``layout: [{voxels: {file: part.npy}}]``).

    python3 -m msfab stack part.npy slices/*.png                 # dark = void, light = material 1
    python3 -m msfab stack part.npy slices/*.png --map 0:0 255:1 128:2

Image k is layer z = k (in the order given); its column is x and its rows
run upwards in y (the bottom row is y = 0, as an image viewer shows the
slice seen from +z). Pixels are read as 8-bit gray levels (colour images
by their luminance, 0.299 R + 0.587 G + 0.114 B). Without ``--map`` a
gray level of 128 or more is material 1, below it void; with ``--map``
every gray level present must be mapped, and an unmapped one is refused
naming the image and the pixel.
"""

import os

import numpy as np

from .artifact import ArtifactError


def _gray_levels(path):
    import matplotlib.image

    try:
        image = matplotlib.image.imread(path)
    except (OSError, ValueError, SyntaxError) as e:
        raise ArtifactError(f"{path}: not a readable image ({e})") from None
    image = np.asarray(image)
    if image.dtype.kind == "f":  # PNG comes as floats in [0, 1]
        image = np.round(image * 255.0)
    image = image.astype(np.float64)
    if image.ndim == 3:
        if image.shape[2] >= 3:
            image = 0.299 * image[:, :, 0] + 0.587 * image[:, :, 1] + 0.114 * image[:, :, 2]
        else:
            image = image[:, :, 0]
    if image.ndim != 2:
        raise ArtifactError(f"{path}: expected a 2D image, got shape {image.shape}")
    return np.clip(np.round(image), 0, 255).astype(np.int64)


def parse_map(entries):
    """{gray level: id} from "level:id" strings."""
    mapping = {}
    for entry in entries:
        level, sep, ident = entry.partition(":")
        try:
            level, ident = int(level), int(ident)
        except ValueError:
            raise ArtifactError(f"--map {entry}: expected GRAY:ID with integers, e.g. 255:1") from None
        if not (sep and 0 <= level <= 255 and ident >= 0):
            raise ArtifactError(f"--map {entry}: the gray level must be 0..255 and the id >= 0")
        mapping[level] = ident
    return mapping


def stack_to_ids(images, mapping=None):
    """The ids array, shape (nx, ny, nz), of the images (layer z = image z)."""
    if not images:
        raise ArtifactError("no images given")
    layers = []
    shape = None
    for path in images:
        gray = _gray_levels(path)
        if shape is None:
            shape = gray.shape
        elif gray.shape != shape:
            raise ArtifactError(f"{path}: {gray.shape[1]} x {gray.shape[0]} pixels, the first image "
                                f"{images[0]} has {shape[1]} x {shape[0]}")
        if mapping is None:
            ids = (gray >= 128).astype(np.int64)
        else:
            ids = np.full(gray.shape, -1, dtype=np.int64)
            for level, ident in mapping.items():
                ids[gray == level] = ident
            if (ids < 0).any():
                row, column = np.argwhere(ids < 0)[0]
                raise ArtifactError(f"{path}: pixel (column {column}, row {row}) has gray level {gray[row, column]}, "
                                    f"which --map does not name (mapped: {sorted(mapping)})")
        layers.append(ids[::-1, :].T)  # rows upwards in y, columns along x
    return np.stack(layers, axis=2)


def write_ids(path, ids):
    """numpy.save through a temporary file, so that a failure leaves no half file."""
    largest = int(ids.max()) if ids.size else 0
    dtype = np.uint8 if largest < 256 else np.uint16 if largest < 65536 else np.int32
    tmp = f"{path}.{os.getpid()}.tmp.npy"
    np.save(tmp, ids.astype(dtype))
    os.replace(tmp, path)
