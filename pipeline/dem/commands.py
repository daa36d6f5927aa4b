"""``ehd export-dem`` and ``ehd restitution`` (registered through ``pipeline.cli.COMMAND_MODULES``)."""


def register(sub) -> None:
    pass
