"""The equations of the model, each physical term written once (docs/model.md)."""
