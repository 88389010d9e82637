"""Scene files: a scene document (:mod:`~rpr3_gwr_core.world.scene`) read
from YAML or JSON."""

from ..documents import read_document
from ..exceptions import InvalidInputError
from ..world.scene import scene_from_dict

__all__ = ["load_scene"]


def load_scene(path):
    """Read a scene file (YAML, or JSON which is YAML).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    Scene

    Raises
    ------
    InvalidInputError
        If the file cannot be read, is not UTF-8 YAML of at most
        :data:`~rpr3_gwr_core.documents.MAX_DOCUMENT_BYTES`
        (:func:`~rpr3_gwr_core.documents.read_document`), or the scene is
        malformed (:func:`~rpr3_gwr_core.world.scene.scene_from_dict`); the
        message names the file.
    """
    try:
        data = read_document(path, "scene")
    except OSError as exc:
        raise InvalidInputError(f"cannot read scene {path}: {exc.strerror or exc}") from None
    try:
        return scene_from_dict({} if data is None else data)
    except InvalidInputError as exc:
        raise InvalidInputError(f"scene {path}: {exc}") from None
