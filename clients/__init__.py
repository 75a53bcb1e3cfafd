"""thrustshape clients: the ``thrustshape`` command line (``clients.cli``) and the HTTP client."""
