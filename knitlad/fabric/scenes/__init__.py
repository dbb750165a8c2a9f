"""Scenes build :class:`knitlad.engine.state.Rods` (a model and its state) for one kind of experiment."""
