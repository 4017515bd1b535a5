"""The users domain: models, schemas, service and router."""
