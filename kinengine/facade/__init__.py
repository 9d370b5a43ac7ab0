"""The Robot facade's method groups beyond the hot path (analysis, model editing, pictures), mixed into
:class:`kinengine.Robot`; each uses only the Robot's public members."""
