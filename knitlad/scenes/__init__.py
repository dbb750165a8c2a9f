"""Scenes build a :class:`knitlad.state.RodState` for one kind of experiment."""
