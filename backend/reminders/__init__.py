"""Reminders of a plan: reminder times in the patient's time zone, today's next one for the patient's page, and
e-mails through a configured SMTP server, each sent once per plan, day and time however many servers run
(a row in reminder_sent claims it before sending), with an unsubscribe link that needs no login."""
