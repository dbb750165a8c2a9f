"""Scenes build :class:`knitlad.state.Rods` (a model and its state) for one kind of experiment."""
