"""The one error the readers raise."""


class FormatError(ValueError):
    """A file that is not a valid svokit file: ``path`` and ``problem``, printed as one line
    "PATH: PROBLEM", as svokit's tools print theirs."""

    def __init__(self, path, problem):
        super().__init__(f"{path}: {problem}")
        self.path = path
        self.problem = problem
