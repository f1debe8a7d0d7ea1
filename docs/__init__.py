"""The project's documentation; :mod:`docs.guide` generates the assembly guide site from the CAD model."""
