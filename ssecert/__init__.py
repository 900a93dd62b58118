"""ssecert: certificates for secure state estimation under sparse sensor attacks."""

__version__ = "0.1.0"

__all__ = ["__version__"]
