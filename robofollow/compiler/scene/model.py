"""The base of RoboFollow's data models: frozen, and strict about fields."""

from pydantic import BaseModel, ConfigDict


class Model(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")
