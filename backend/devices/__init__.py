"""The devices domain: models, schemas, service and router."""
