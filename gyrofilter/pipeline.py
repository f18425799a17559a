"""Placeholder while the pipeline is written (replaced in the next commit)."""


class GyroFilter:
    def __init__(self, *args, **kwargs):
        raise NotImplementedError("the pipeline is being written")
