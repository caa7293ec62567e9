from ._vibro import version as __version__
