"""Printed and machined parts. Each module turns the :class:`~cad.layout.Layout` into a frozen spec
(plain numbers: its complete cache key) whose ``build()`` makes the solid, and says how it prints."""
