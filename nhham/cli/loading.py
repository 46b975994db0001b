"""The command's scene: loaded with the command line's ``--set`` values."""

from __future__ import annotations

from nhham.errors import InputError, UsageError

__all__ = ["load_for"]


def load_for(args, *, singular: bool = False, **options):
    """The command's scene: :func:`nhham.system.scene.load_scene` with its ``--set``
    values (``args.parameter_values``); a name there that is not a parameter is a usage
    error of ``--set`` (exit 2, the closest name suggested). A singular Lagrangian is
    refused (``SingularLagrangianError``, exit 2) unless the command answers it
    (``singular=True``: ``classify``)."""
    from nhham.system.scene import load_scene

    try:
        scene = load_scene(args.scene, values=getattr(args, "parameter_values", None),
                           **options)
    except InputError as exc:
        if exc.key != "values":
            raise
        raise UsageError(str(exc).replace("values: ", "--set: ", 1), key="--set") from None
    if not singular:
        scene.system.require_regular_lagrangian(f"nhham {args.command}")
    return scene
