"""The command's scene: loaded with the command line's ``--set`` values."""

from __future__ import annotations

from nhham.errors import InputError, UsageError

__all__ = ["load_for"]


def load_for(args, **options):
    """The command's scene: :func:`nhham.system.scene.load_scene` with its ``--set``
    values (``args.parameter_values``); a name there that is not a parameter is a usage
    error of ``--set`` (exit 2, the closest name suggested)."""
    from nhham.system.scene import load_scene

    try:
        return load_scene(args.scene, values=getattr(args, "parameter_values", None),
                          **options)
    except InputError as exc:
        if exc.key != "values":
            raise
        raise UsageError(str(exc).replace("values: ", "--set: ", 1), key="--set") from None
