"""The FMU: variable declarations, model configuration, models and the pythonfmu adapter.

``variables`` declares every FMU variable once; ``config`` says which model a built FMU
holds; ``body_model``, ``contact_model`` and ``rigid_body`` are the models behind the
three kinds of FMU; ``slave`` is the only module of the project that imports
pythonfmu. Nothing here is imported by the numerical core.
"""
