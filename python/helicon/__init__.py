"""placeholder"""
from ._helicon import *  # noqa
