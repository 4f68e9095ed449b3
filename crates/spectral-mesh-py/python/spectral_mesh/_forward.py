"""Read-only attributes that the Python classes answer from their native object."""

from __future__ import annotations

from typing import Any, Generic, TypeVar, overload

T = TypeVar("T")


class NativeAttribute(Generic[T]):
    """A read-only attribute answered by the attribute ``name`` (default: the one it is
    assigned to) of the instance's native object ``_native``, documented by ``doc``."""

    def __init__(self, doc: str, name: str | None = None) -> None:
        self.__doc__ = doc
        self._name = name or ""

    def __set_name__(self, owner: type, name: str) -> None:
        self._name = self._name or name

    @overload
    def __get__(self, obj: None, owner: type | None = None) -> NativeAttribute[T]: ...

    @overload
    def __get__(self, obj: object, owner: type | None = None) -> T: ...

    def __get__(self, obj: object | None, owner: type | None = None) -> Any:
        if obj is None:
            return self
        return getattr(getattr(obj, "_native"), self._name)
