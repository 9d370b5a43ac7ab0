"""The presentation layer: pictures of a robot (matplotlib skeletons; the browser viewer)."""
