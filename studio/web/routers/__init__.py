"""One router per resource; :func:`studio.web.create_app` includes them all."""
